"""Trivial nodes for measuring the scheduler's own cost per node."""

from graphvision import Float, node


@node("bench.inc")
def inc(x: Float) -> Float:
    """x + 1."""
    return x + 1.0
