"""Choosing each node's implementation: the backend lookup order of a run.

The order comes from, first found: ``backends=`` of :func:`~graphvision.run` (the
command line's ``--backend opencv,numpy``), the pipeline file's ``backends:``, else
the reference alone (``numpy``). Each node runs with the first backend of the order
that implements its op and is installed; the reference, which implements every op,
ends every order, so an op no backend of the order has runs as it always did. A node's
``backend:`` pins it: an op the backend lacks, or a backend whose library is not
installed, is then a validation problem at the node's line (naming the extra to
install, or the reason a check of its ``requires`` gives), never a silent fallback.
A backend name no plugin provides is a problem too (with a close match): a typo must
not silently run the reference. A parameter value one backend alone handles (its
``exclusive``, as OpenCV's ``method: magsac``) is a problem on any other backend.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from graphvision.errors import RegistrationError, did_you_mean
from graphvision.nodes.backends import REFERENCE, exclusive_problem, unavailable
from graphvision.nodes.registry import Registry
from graphvision.nodes.spec import NodeSpec

__all__ = ["BackendChooser", "close_backend", "known_backends"]


def close_backend(name: str, names: Iterable[str]) -> str:
    """``" (did you mean 'opencv'?)"`` for ``name`` among the backend ``names``, case
    aside (backend names are lower case: ``OpenCV`` is ``opencv``), or ''."""
    return did_you_mean(name.lower(), names)


def indexed_implementations() -> set[str]:
    """Every ``op@backend`` the plugin index lists for the installed plugins (read from
    the index, nothing imported; empty without a sound index)."""
    from graphvision.nodes.plugin_index import (
        environment_key,
        has_index,
        installed_entry_points,
        read_providers,
    )

    key = environment_key(installed_entry_points())
    providers = read_providers(key) if has_index(key) else None
    entries = (providers or {}).values()
    return {item for entry in entries for item in entry.get("implementations", [])}


def known_backends(registry: Registry) -> set[str]:
    """The backends of ``registry`` and those the plugin index lists for the installed
    plugins: a run loads only the plugins of its backends, so a name is unknown only if
    no installed plugin provides it."""
    return registry.backends() | {item.partition("@")[2] for item in indexed_implementations()}


class BackendChooser:
    """The implementation of each node, for one lookup order against one registry."""

    def __init__(self, registry: Registry, order: Sequence[str]) -> None:
        self.registry = registry
        self.given = list(order)
        self.order = [*dict.fromkeys(order)]
        if REFERENCE not in self.order:
            self.order.append(REFERENCE)

    def order_problems(self) -> list[str]:
        """One message per name of the order that is empty, named twice, or that no
        plugin provides (loaded, or listed by the plugin index)."""
        problems = [
            f"backend '{name}' is named {self.given.count(name)} times in the order; "
            "name each once (the order says which backend to try first)"
            for name in self.order
            if name and self.given.count(name) > 1
        ]
        if "" in self.given:
            problems.append("an empty backend name in the order; name each backend once")
        if all(name in self.registry.backends() for name in self.order if name):
            return problems
        known = known_backends(self.registry)
        return problems + [
            f"unknown backend '{name}'{close_backend(name, known)}; "
            f"backends: {', '.join(sorted(known))}"
            for name in self.order
            if name and name not in known
        ]

    def choose(
        self, spec: NodeSpec, pinned: str, params: Mapping[str, Any] | None = None
    ) -> tuple[NodeSpec, str]:
        """(the implementation to run, '') or (the reference, the problem with the pin);
        ``params`` (the node's, validated) are checked against what each backend handles."""
        try:
            chosen, problem = self._pinned(spec, pinned) if pinned else (self._first(spec), "")
        except RegistrationError as error:
            return spec, str(error)
        if problem:
            return chosen, problem
        others = self.registry.exclusive_of(spec.id)  # loaded, or in the plugin index
        return chosen, exclusive_problem(spec.id, chosen.backend, others, params or {})

    def _first(self, spec: NodeSpec) -> NodeSpec:
        """The implementation of the first backend of the order that can run here."""
        impls = self.registry.implementations.get(spec.id, {})
        for backend in self.order:
            impl = self.registry.implementation(spec.id, backend)
            if impl is not None and (backend == REFERENCE or not unavailable(impls[backend])):
                return impl
        return spec  # pragma: no cover - the reference ends every order

    def _pinned(self, spec: NodeSpec, backend: str) -> tuple[NodeSpec, str]:
        available = self.registry.backends_of(spec.id)
        if backend not in available:
            # a pin the run's plugins cannot serve: name every installed backend of the op
            indexed = (item.partition("@") for item in indexed_implementations())
            others = {b for op, _, b in indexed if op == spec.id and b not in available}
            names = [*available, *sorted(others)]
            return spec, (
                f"{spec.id} has no '{backend}' implementation"
                f"{close_backend(backend, names)}; backends: {', '.join(names)}"
            )
        impl = self.registry.implementation(spec.id, backend)
        if impl is None:  # pragma: no cover - backends_of lists only registered ones
            return spec, f"{spec.id} has no '{backend}' implementation"
        registered = self.registry.implementations.get(spec.id, {}).get(backend)
        reason = unavailable(registered) if registered is not None else ""
        if reason and registered is not None:
            state = "is not installed" if reason.endswith("not found") else "cannot run here"
            return spec, (
                f"backend '{backend}' of {spec.id} {state} ({reason}): {registered.install_hint}"
            )
        return impl, ""
