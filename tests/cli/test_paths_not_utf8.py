"""A run whose files would name a path that is not UTF-8 is refused before anything runs:
record.json, batch.csv and the pages are UTF-8. Through the working folder too (found by
the tryer: a run from a folder named cwd\\xff computed everything, then could not write)."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest

from graphvision.cli import main

from ..conftest import PIPELINES

DEMO = PIPELINES / "denoise.yaml"


@pytest.fixture
def latin_folder(tmp_path, monkeypatch):
    """The working folder ``cwd\\xff`` (not UTF-8), holding the demo pipeline and a photo."""
    folder = Path(os.fsdecode(bytes(tmp_path) + b"/cwd\xff"))
    (folder / "photos").mkdir(parents=True)
    shutil.copy(DEMO, folder / "p.yaml")
    iio.imwrite(folder / "photos" / "a.png", np.full((16, 16), 90, np.uint8))
    monkeypatch.chdir(folder)
    return folder


@pytest.mark.parametrize(
    ("args", "said"),
    [
        (["p.yaml", "-d", "out"], "pipeline file {cwd}/p.yaml: its path is not UTF-8"),
        ([str(DEMO), "-d", "out"], "--output-dir out\\xff: its path is not UTF-8"),
        (
            [str(DEMO), "-d", "{tmp}/o", "-i", "image=photos/a.png"],
            "--input image {cwd}/photos/a.png: its path is not UTF-8",
        ),
        (
            [str(DEMO), "-d", "{tmp}/o", "--batch", "image=photos/*.png"],
            "1 file name(s) are not UTF-8 (such as {cwd}/photos/a.png)",
        ),
    ],
    ids=["pipeline", "output", "input", "batch"],
)
def test_a_path_not_utf8_through_the_working_folder_is_refused_up_front(
    capsys, tmp_path, latin_folder, args, said
):
    cwd = os.fsencode(latin_folder).decode("utf-8", "backslashreplace")
    given = [a.replace("{tmp}", str(tmp_path)) for a in args]
    before = sorted(os.listdir(latin_folder))
    assert main(["run", *given, "--no-cache"]) == 2
    err = capsys.readouterr().err
    expected = said.format(cwd=cwd).replace("out\\xff", f"{cwd}/out")
    assert err.startswith("error: ") and expected in err, err
    assert "Traceback" not in err and "internal error" not in err
    assert sorted(os.listdir(latin_folder)) == before  # nothing made
    assert not (tmp_path / "o").exists()


def test_an_input_named_not_utf8_is_refused_though_missing(capsys, tmp_path):
    name = os.fsdecode(b"caf\xe9.png")
    args = ["run", str(DEMO), "-d", str(tmp_path / "o"), "-i", f"image={name}", "--no-cache"]
    assert main(args) == 2
    assert "error: --input image caf\\xe9.png: its path is not UTF-8" in capsys.readouterr().err


PLUGIN = '''from graphvision import GrayImage, node


@node("own.half")
def half(image: GrayImage) -> GrayImage:
    """Half of each pixel."""
    return image / 2
'''


@pytest.mark.parametrize("command", ["run", "validate", "nodes"])
def test_a_plugin_named_not_utf8_is_refused_up_front(capsys, tmp_path, latin_folder, command):
    """It was a warning (its import failed on the name), then every node of it unknown."""
    (latin_folder / "own.py").write_text(PLUGIN)
    cwd = os.fsencode(latin_folder).decode("utf-8", "backslashreplace")
    tail = [str(DEMO), "-d", str(tmp_path / "o")] if command == "run" else []
    tail = [str(DEMO)] if command == "validate" else tail
    assert main([command, "--plugins", "own.py", *tail]) == 2
    err = capsys.readouterr().err
    assert err == (
        f"error: --plugins {cwd}/own.py: its path is not UTF-8; a plugin is loaded and "
        "recorded by its path in UTF-8: rename it or its folder\n"
    )
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("command", ["run", "cache"])
def test_a_cache_folder_not_utf8_is_refused_up_front(capsys, tmp_path, command):
    """It was used, and ``cache info`` then ended with an internal error (UTF-8 stdout)."""
    cache = os.fsdecode(bytes(tmp_path) + b"/cache\xff")
    args = [str(DEMO), "-d", str(tmp_path / "o")] if command == "run" else ["info"]
    assert main([command, *args, "--cache-dir", cache]) == 2
    assert capsys.readouterr().err == (
        f"error: --cache-dir {tmp_path}/cache\\xff: its path is not UTF-8; cache info and the "
        "messages about the cache name it in UTF-8: rename it or its folder\n"
    )
    assert sorted(os.listdir(tmp_path)) == []


@pytest.mark.parametrize("variable", ["GRAPHVISION_CACHE_DIR", "XDG_CACHE_HOME"])
@pytest.mark.parametrize("command", ["run", "cache"])
def test_a_cache_folder_not_utf8_from_the_environment_is_refused(
    capsys, tmp_path, monkeypatch, command, variable
):
    """``cache info`` ended with an internal error on a UTF-8 stdout."""
    monkeypatch.delenv("GRAPHVISION_CACHE_DIR", raising=False)
    monkeypatch.setenv(variable, os.fsdecode(bytes(tmp_path) + b"/c\xff"))
    args = [str(DEMO), "-d", str(tmp_path / "o")] if command == "run" else ["info"]
    assert main([command, *args]) == 2
    shown = f"{tmp_path}/c\\xff" + ("/graphvision" if variable == "XDG_CACHE_HOME" else "")
    assert capsys.readouterr().err == (
        f"error: the cache folder (from ${variable}) {shown}: its path is not UTF-8; cache info "
        "and the messages about the cache name it in UTF-8: rename it or its folder\n"
    )
    assert sorted(os.listdir(tmp_path)) == []


def test_a_run_without_a_cache_does_not_look_at_the_cache_folder(tmp_path, monkeypatch):
    monkeypatch.setenv("GRAPHVISION_CACHE_DIR", os.fsdecode(bytes(tmp_path) + b"/c\xff"))
    args = ["-d", str(tmp_path / "o"), "--no-cache", "-o", "psnr_noisy_gaussian"]
    assert main(["run", str(DEMO), *args]) == 0


def test_a_plugin_folder_holding_a_file_not_utf8_is_refused_up_front(capsys, tmp_path):
    """It was a warning naming graphvision's own loading line as the plugin's, then unknown ops."""
    folder = tmp_path / "plg"
    folder.mkdir()
    (folder / "fine.py").write_text(PLUGIN)
    Path(os.fsdecode(bytes(folder) + b"/q\xff.py")).write_text(PLUGIN)
    assert main(["run", str(DEMO), "-d", str(tmp_path / "o"), "--plugins", str(folder)]) == 2
    assert capsys.readouterr().err.startswith(
        f"error: --plugins {folder}/q\\xff.py: its path is not UTF-8; "
    )


def test_a_plugin_file_not_utf8_fails_to_load_naming_it_from_python(tmp_path):
    from graphvision.nodes.plugins import discover

    folder = tmp_path / "plg"
    folder.mkdir()
    Path(os.fsdecode(bytes(folder) + b"/q\xff.py")).write_text(PLUGIN)
    (failed,) = discover([folder], entry_points=False).failed_plugins()
    assert failed.error == f"plugin {folder}/q\\xff.py: its path is not UTF-8: rename it"


def test_validate_refuses_a_pipeline_whose_path_is_not_utf8_as_run_does(capsys, latin_folder):
    """validate named it with a surrogate and went on to its plugins, where run refused it."""
    cwd = os.fsencode(latin_folder).decode("utf-8", "backslashreplace")
    assert main(["validate", "p.yaml"]) == 2
    assert capsys.readouterr().err.startswith(
        f"error: pipeline file {cwd}/p.yaml: its path is not UTF-8; "
    )


def test_a_package_plugin_holding_a_module_not_utf8_loads(tmp_path):
    """The package's digest encoded its files' names as UTF-8: the whole package failed to
    load (``UnicodeEncodeError``, no file named) for a module it never imports (found by
    TRY45). Its own modules are imported by Python's names, which are UTF-8."""
    from graphvision.nodes.plugins import discover

    package = tmp_path / "pkgp" / "mypkg"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text(PLUGIN)
    Path(os.fsdecode(bytes(package) + b"/b\xe9d.py")).write_text("raise SystemExit(3)\n")
    registry = discover([package], entry_points=False)
    assert registry.failed_plugins() == []
    assert registry.node("own.half").id == "own.half"


def _latin(folder: Path, name: bytes) -> Path:
    return Path(os.fsdecode(bytes(folder) + b"/" + name))


def _plugin_layouts(tmp_path: Path) -> dict[str, tuple[str, str]]:
    """Plugins given by a UTF-8 path whose loading reads a path that is not: each with the
    path ``--plugins`` names and what the refusal names."""
    package = _latin(tmp_path, b"pack\xff")
    package.mkdir()
    (package / "__init__.py").write_text("")
    (tmp_path / "to_package").symlink_to(package)
    flat = tmp_path / "flat"
    flat.mkdir()
    (flat / "m.py").symlink_to(package / "__init__.py")
    return {  # each given from tmp_path
        "a link to a folder": ("to_package", f"to_package leads to {tmp_path}/pack\\xff"),
        "a file that is a link": ("flat", f"flat/m.py leads to {tmp_path}/pack\\xff/__init__.py"),
    }


@pytest.mark.parametrize(
    "layout",
    ["a link to a folder", "a file that is a link"],
)
@pytest.mark.parametrize("command", ["run", "validate"])
def test_a_plugin_read_through_a_path_not_utf8_is_refused_up_front(
    capsys, tmp_path, monkeypatch, layout, command
):
    """As a folder named so is: it was a warning (the loader resolves links), then an
    unknown op. (A package's own module named so is not read by name: the package loads.)"""
    given, named = _plugin_layouts(tmp_path)[layout]
    monkeypatch.chdir(tmp_path)
    tail = ["-d", str(tmp_path / "o")] if command == "run" else []
    assert main([command, str(DEMO), *tail, "--plugins", given]) == 2
    assert capsys.readouterr().err == (
        f"error: --plugins {named}: its path is not UTF-8; a plugin is loaded and recorded by "
        "its path in UTF-8: rename it or its folder\n"
    )
    assert not (tmp_path / "o").exists()


def test_a_package_plugin_holding_a_module_not_utf8_runs(tmp_path):
    """The run's provenance digested the package's files' names as UTF-8: every run ended
    with an internal error (found by TRY45b)."""
    package = tmp_path / "mypkg"
    package.mkdir()
    (package / "__init__.py").write_text(PLUGIN)
    Path(os.fsdecode(bytes(package) + b"/\xe9d.py")).write_text("X = 1\n")
    (tmp_path / "p.yaml").write_text(
        "version: 1\nname: p\nplugins: [mypkg]\n"
        "inputs: {image: {type: GrayImage, default: 'sample:camera'}}\n"
        "nodes: {h: {op: own.half, in: {image: image}}}\noutputs: {half: h}\n"
    )
    assert main(["run", str(tmp_path / "p.yaml"), "-d", str(tmp_path / "o"), "--no-cache"]) == 0
    assert (tmp_path / "o" / "record.json").is_file()
