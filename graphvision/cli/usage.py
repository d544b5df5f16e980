"""The command line's usage error (a module of its own: the modules of ``graphvision.cli``
raise it, and :mod:`graphvision.cli.common` imports some of them)."""

from graphvision.errors import GraphvisionError


class UsageError(GraphvisionError):
    """A command-line mistake (exit status 2)."""
