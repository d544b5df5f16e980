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
    """Truth input or marked node -> the inputs given without it, for each one missing (a
    node's truth, written into the pipeline, is missing whenever one of them is given)."""
    missing = {}
    for name, truth_of in compiled.truth_marks:
        subjects = [subject for subject in truth_of if subject in given]
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
        node = truth in compiled.graph.nodes
        needing = [o for o in wanted if _reads(compiled, o, truth, node)]
        if not needing:
            continue
        what = (
            f"node '{truth}', whose truth" if node else f"the ground truth '{truth}': its default"
        )
        why = (
            f"need{'s' if len(needing) == 1 else ''} {what} "
            f"goes with the default {', '.join(subjects)} only, and "
            f"{'it was' if len(subjects) == 1 else 'they were'} given"
        )
        how = (
            "the pipeline holds no truth for yours, so nothing can"
            if node
            else f"give input {truth} (--input {truth}=FILE) to"
        ) + " compute"
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


def _reads(compiled: CompiledGraph, output: str, truth: str, node: bool) -> bool:
    """Whether ``output`` reads the truth input or the marked node ``truth``."""
    schedule = compiled.schedule_for([output])
    return truth in (schedule.steps if node else schedule.inputs)
