"""The paths a command names in its messages, records and pages, refused before anything
runs when one is not UTF-8 (its bytes shown escaped: ``out\\xff``): a run that computed
everything could not write them."""

from __future__ import annotations

import os
from pathlib import Path

from graphvision.cli.usage import UsageError


def plugin_paths(path: Path) -> list[tuple[Path, Path]]:
    """Each path the loading of the local plugin ``path`` reads, as given and as read (its
    links followed, as the loader follows them): ``path``, each file a folder of ``.py``
    files imports (:func:`~graphvision.nodes.plugins.plugin_files`)."""
    from graphvision.nodes.plugins import plugin_files

    given = [path, *plugin_files(path)]
    return [(file, file.resolve()) for file in given]


def refuse_paths_not_utf8(pipeline: str, inputs: dict[str, str]) -> None:
    """A usage error for the pipeline file or an ``--input`` whose path is not UTF-8 (in
    itself, or through the working folder when it is a file there: an input may be a
    source such as ``sample:camera``): record.json and the pages name them in UTF-8, and a
    run that computed everything could not write them."""
    given = [("pipeline file", pipeline)] + [(f"--input {k}", v) for k, v in inputs.items()]
    for what, text in given:
        why = "record.json and the pages name it in UTF-8"
        refuse_not_utf8(what, text, why, through_working_folder=Path(text).exists())


def refuse_cache_dir_not_utf8(folder: str | None) -> None:
    """A usage error for a cache folder whose path is not UTF-8 (in itself or through the
    working folder): ``--cache-dir``, else the environment's (``$GRAPHVISION_CACHE_DIR``,
    ``$XDG_CACHE_HOME``); ``cache info`` and the messages about the cache name it in UTF-8
    (in a UTF-8 locale, ``cache info`` ended with an internal error)."""
    from graphvision.locations import default_cache_dir

    if folder is not None:
        what = "--cache-dir"
    else:
        folder = str(default_cache_dir())
        variable = next(
            (name for name in ("GRAPHVISION_CACHE_DIR", "XDG_CACHE_HOME") if os.environ.get(name)),
            "HOME",
        )
        what = f"the cache folder (from ${variable})"
    refuse_not_utf8(what, folder, "cache info and the messages about the cache name it in UTF-8")


def refuse_not_utf8(what: str, text: str, why: str, through_working_folder: bool = True) -> None:
    """A usage error naming ``what`` when the path ``text`` is not UTF-8, in itself or
    (``through_working_folder``) through the working folder; ``why`` it must be."""
    from graphvision.locations import not_utf8

    path = Path(text)
    shown = not_utf8(path) or (not_utf8(path.absolute()) if through_working_folder else None)
    if shown is not None:
        raise UsageError(f"{what} {shown}: its path is not UTF-8; {why}: rename it or its folder")
