"""``python -m graphvision.cli``: the command line."""

from graphvision.cli import entry

entry()
