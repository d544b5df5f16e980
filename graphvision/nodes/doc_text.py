"""A docstring as plain text: inline LaTeX as Unicode, reStructuredText roles unmarked, and
its summary sentence (what ``graphvision nodes`` lists)."""

from __future__ import annotations

import inspect
import re

__all__ = ["doc_summary", "math_text", "plain_text"]


# -- a docstring's summary as plain text ---------------------------------------------------

_SYMBOLS = {
    "times": "×", "cdot": "·", "pm": "±", "mid": "|", "|": "‖", "lceil": "⌈", "rceil": "⌉",
    "lfloor": "⌊", "rfloor": "⌋", "sum": " Σ", "prod": " Π", "int": "∫", "sqrt": "√",
    "le": "≤", "leq": "≤", "ge": "≥", "geq": "≥", "neq": "≠", "ne": "≠", "approx": "≈",
    "infty": "∞", "in": "∈", "to": "→", "rightarrow": "→", "leftarrow": "←", "nabla": "∇",
    "partial": "∂", "circ": "∘", "star": "⋆", "ast": "∗", "propto": "∝", "sim": "∼",
    "alpha": "α", "beta": "β", "gamma": "γ", "delta": "δ", "epsilon": "ε", "varepsilon": "ε",
    "zeta": "ζ", "eta": "η", "theta": "θ", "kappa": "κ", "lambda": "λ", "mu": "μ", "nu": "ν",
    "xi": "ξ", "pi": "π", "rho": "ρ", "sigma": "σ", "tau": "τ", "phi": "φ", "varphi": "φ",
    "chi": "χ", "psi": "ψ", "omega": "ω", "Gamma": "Γ", "Delta": "Δ", "Theta": "Θ",
    "Lambda": "Λ", "Sigma": "Σ", "Phi": "Φ", "Psi": "Ψ", "Omega": "Ω", "ell": "ℓ",
    ",": " ", ";": " ", ":": " ", "!": "", " ": " ", "quad": " ", "qquad": " ",
    "left": "", "right": "", "big": "", "Big": "", "{": "(", "}": ")", "_": "_", "%": "%",
}  # fmt: skip
_ACCENTS = {"tilde": "\u0303", "hat": "\u0302", "bar": "\u0304", "dot": "\u0307", "vec": "\u20d7"}
_SUPERSCRIPTS = dict(zip("0123456789+-=()nTi", "⁰¹²³⁴⁵⁶⁷⁸⁹⁺⁻⁼⁽⁾ⁿᵀⁱ", strict=True))
_SUBSCRIPTS = dict(zip("0123456789+-=()aehijklmnoprstuvx", "₀₁₂₃₄₅₆₇₈₉₊₋₌₍₎ₐₑₕᵢⱼₖₗₘₙₒₚᵣₛₜᵤᵥₓ"))  # noqa: B905
_GROUP = r"\{([^{}]*)\}"
_ABBREVIATIONS = ("e.g.", "i.e.", "cf.", "vs.", "etc.", "al.", "Fig.", "Eq.", "approx.", "resp.")


def math_text(tex: str) -> str:
    """Inline LaTeX as Unicode text: ``l = v_1 \\times v_2`` -> ``l = v₁ × v₂``."""
    part = lambda t: t if re.fullmatch(r"\w+", t.strip()) else f"({t})"  # noqa: E731
    text = re.sub(rf"\\frac\s*{_GROUP}\s*{_GROUP}", lambda m: f"{part(m[1])}/{part(m[2])}", tex)
    text = re.sub(rf"\\(?:mathrm|text|operatorname|math[a-z]+|boldsymbol)\s*{_GROUP}", r"\1", text)
    accents = "|".join(_ACCENTS)
    text = re.sub(
        rf"\\({accents})\s*(?:{_GROUP}|(\\?[A-Za-z]))",
        lambda m: (m[2] or m[3]) + _ACCENTS[m[1]],
        text,
    )
    text = re.sub(r"\\([A-Za-z]+|.)", lambda m: _SYMBOLS.get(m[1], m[1]), text)
    text = re.sub(rf"\^\s*(?:{_GROUP}|(.))", lambda m: _script(m, _SUPERSCRIPTS, "^"), text)
    text = re.sub(rf"_\s*(?:{_GROUP}|(.))", lambda m: _script(m, _SUBSCRIPTS, "_"), text)
    text = text.replace("{", "").replace("}", "").replace("'", "′")
    return re.sub(r" {2,}", " ", text).strip()


def _script(match: re.Match[str], table: dict[str, str], mark: str) -> str:
    """A super- or subscript in Unicode when every character has one, else ``^(…)``/``_…``."""
    body = match[1] if match[1] is not None else match[2]
    if body and all(c in table for c in body):
        return "".join(table[c] for c in body)
    return f"{mark}{body}" if len(body) == 1 else f"{mark}({body})"


def plain_text(text: str) -> str:
    """reStructuredText as plain text: inline math as Unicode (:func:`math_text`), roles as
    their target's last name (``:func:`~a.b``` -> ``b``), literals and emphasis unmarked."""
    last = lambda t: t.rsplit(".", 1)[-1] if re.fullmatch(r"[\w.]+", t) else t  # noqa: E731
    text = re.sub(r":math:`([^`]*)`", lambda m: math_text(m[1]), text)
    text = re.sub(r":[a-z]+:`~?([^`<]*?)(?:\s*<[^`]*>)?`", lambda m: last(m[1]), text)
    text = text.replace("``", "")
    return re.sub(r"(?<![\w*])\*{1,2}(\S(?:[^*]*\S)?)\*{1,2}(?![\w*])", r"\1", text)


def doc_summary(doc: str) -> str:
    """The first sentence of a docstring's first paragraph, whole, as plain text.

    The paragraph's lines are joined (a sentence wrapped over lines is not cut),
    reStructuredText and inline LaTeX become text (:func:`plain_text`), and a
    pointer to the source ("(module docstring)", "(see the module docstring)",
    "(module ``_projection``)") is dropped: a summary is read in a listing.
    """
    paragraph = inspect.cleandoc(doc or "").split("\n\n", 1)[0]
    text = " ".join(plain_text(" ".join(paragraph.split())).split())
    text = _without_source_pointers(text)
    sentence = _first_sentence(text)
    if sentence and sentence[-1] not in ".!?":
        sentence += "."
    return sentence


def _without_source_pointers(text: str) -> str:
    pointer = r"(?:see )?(?:the )?module(?: docstring| _?\w+)?"

    def keep(match: re.Match[str]) -> str:
        parts = [p for p in match.group(1).split(",") if not re.fullmatch(pointer, p.strip())]
        if len(parts) == match.group(1).count(",") + 1:
            return match.group(0)
        return f" ({','.join(parts).strip()})" if parts else ""

    return re.sub(r"\s*\(([^()]*)\)", keep, text)


def _first_sentence(text: str) -> str:
    """Up to the first full stop followed by a capital, outside brackets and abbreviations."""
    depth = 0
    for index, char in enumerate(text):
        depth += (char in "([") - (char in ")]")
        before, after = text[: index + 1], text[index + 1 : index + 3]
        ends = char in ".!?" and not depth and re.fullmatch(r" [A-Z]", after)
        if ends and not before.endswith(_ABBREVIATIONS):
            return before
    return text
