"""graphvision studio: see every intermediate and tune a pipeline live in the browser.

A layer above :mod:`graphvision.views` and beside :mod:`graphvision.cli`: a local web
server (Starlette and uvicorn, in the ``studio`` extra, imported only when the studio
starts) over one :class:`~graphvision.studio.session.Session`. The page and its viewers
are built from ``frontend/`` into ``static/`` (see ``frontend/build.mjs``).
"""
