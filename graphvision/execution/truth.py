"""Outputs that need ground truth (issue 29 item 9).

A pipeline input marked ``truth_of: [left, right]`` is the ground truth of those
inputs: its default (``sample:motorcycle_disparity``) is the truth of *their* defaults
(the sample pair) and of nothing else. When a run is given one of them (the user's own
pair) and not the truth, the truth is missing: every output that reads it, directly or
through nodes, is skipped, with one line saying which, why, and how to give the truth
(a :class:`MissingTruthWarning`, shown as ``warning: ...`` on the command line); the
other outputs run. Asking for such an output by name (``-o bad2``) without its truth is
an :class:`~graphvision.errors.InputError` (exit 2), before anything runs.
"""

from __future__ import annotations

import warnings

from graphvision.compiler.compile import CompiledGraph
from graphvision.errors import InputError

__all__ = ["MissingTruthWarning", "missing_truth", "outputs_with_truth"]


class MissingTruthWarning(UserWarning):
    """Outputs were skipped: they need ground truth that the run was not given."""


def missing_truth(compiled: CompiledGraph, given: set[str]) -> dict[str, list[str]]:
    """Truth input -> the inputs given without it, for each truth input that is missing."""
    missing = {}
    for name, decl in compiled.graph.inputs.items():
        subjects = [subject for subject in decl.truth_of if subject in given]
        if subjects and name not in given:
            missing[name] = subjects
    return missing


def outputs_with_truth(
    compiled: CompiledGraph, wanted: list[str], given: set[str], asked: bool
) -> list[str]:
    """``wanted`` without the outputs whose ground truth is missing (one warning per missing
    truth); when the outputs were ``asked`` for by name, an InputError instead."""
    missing = missing_truth(compiled, given)
    if not missing:
        return wanted
    kept = list(wanted)
    for truth, subjects in missing.items():
        needing = [o for o in wanted if truth in compiled.schedule_for([o]).inputs]
        if not needing:
            continue
        why = (
            f"need{'s' if len(needing) == 1 else ''} the ground truth '{truth}': its default "
            f"goes with the default {', '.join(subjects)} only, and "
            f"{'it was' if len(subjects) == 1 else 'they were'} given"
        )
        how = f"give input {truth} (--input {truth}=FILE) to compute"
        one = len(needing) == 1
        listed = f"output{'' if one else 's'} {', '.join(needing)}"
        if asked:
            raise InputError(f"{listed} {why}: {how} {'it' if one else 'them'}")
        warnings.warn(
            f"skipped {listed}: {'it' if one else 'they'} {why}; {how} {'it' if one else 'them'}",
            MissingTruthWarning,
            stacklevel=3,
        )
        kept = [o for o in kept if o not in needing]
    return kept
