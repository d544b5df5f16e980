"""The command line: ``graphvision run|sweep|validate|nodes|describe|schema|graph|report|cache``."""

from graphvision.cli.main import entry, main

__all__ = ["entry", "main"]
