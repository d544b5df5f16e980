"""``python -m graphvision``: the command line."""

from graphvision.cli import entry

entry()
