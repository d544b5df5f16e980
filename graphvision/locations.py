"""Where graphvision keeps what it caches, without importing the cache itself."""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["default_cache_dir"]


def default_cache_dir() -> Path:
    """``$GRAPHVISION_CACHE_DIR``, else ``$XDG_CACHE_HOME/graphvision``, else ``~/.cache/...``."""
    if os.environ.get("GRAPHVISION_CACHE_DIR"):
        return Path(os.environ["GRAPHVISION_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "graphvision"
