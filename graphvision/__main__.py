"""``python -m graphvision``: the command line."""

from .cli import entry

entry()
