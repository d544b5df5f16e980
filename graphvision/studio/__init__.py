"""graphvision studio: see every intermediate and tune a pipeline live in the browser.

A layer above :mod:`graphvision.views` and beside :mod:`graphvision.cli`: a local web
server (Starlette and uvicorn, in the ``studio`` extra, imported only when the studio
starts) over one :class:`~graphvision.studio.session.Session`. The page and its viewers
are built from ``frontend/`` into ``static/`` (see ``frontend/build.mjs``).
"""

from __future__ import annotations

import sys
import types
from typing import Any


class _Studio(types.ModuleType):
    """This package, callable: ``gv.studio(pipeline)`` is :func:`.server.studio`.

    ``graphvision.studio`` names both the package and the function: once the package is
    imported, Python sets the package as the attribute ``studio`` of ``graphvision``, so
    the package itself takes the call (see :func:`graphvision.studio.server.studio`).
    """

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        from graphvision.studio.server import studio

        return studio(*args, **kwargs)


sys.modules[__name__].__class__ = _Studio
