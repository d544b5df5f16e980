"""The batch's glob: on a tree without links, exactly Python's recursive glob; with links,
each real folder searched once."""

from __future__ import annotations

import glob
import os

import pytest

from graphvision.execution.folder_glob import glob_once

PATTERNS = [
    "ph/**/*.png", "ph/**", "**", "**/*.png", "ph/*/**/*.png", "ph/**/deep/*.png",
    "ph/**/**/*.png", "ph/*.png", "p*/**/b.png", "ph/**/sub", "ph/**/[bc].png", "ph/**/",
    "**/",
]  # fmt: skip


@pytest.fixture
def tree(tmp_path, monkeypatch):
    for name in ["ph/a.png", "ph/sub/b.png", "ph/sub/deep/c.png", "ph/.hid.png", "ph/.h/d.png"]:
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_bytes(b"x")
    (tmp_path / "ph" / "[odd]").mkdir()
    (tmp_path / "ph" / "[odd]" / "e.png").write_bytes(b"x")
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("pattern", PATTERNS)
def test_without_links_it_matches_what_pythons_recursive_glob_matches(tree, pattern):
    assert sorted(glob_once(pattern)) == sorted(glob.glob(pattern, recursive=True))
    absolute = os.path.join(str(tree), pattern)
    assert sorted(glob_once(absolute)) == sorted(glob.glob(absolute, recursive=True))


def test_a_folder_reached_again_is_not_searched_below(tree):
    os.symlink("..", "ph/sub/up")
    os.symlink("sub", "ph/sub2")
    found = sorted(glob_once("ph/**/*.png"))
    assert found == [
        "ph/[odd]/e.png", "ph/a.png", "ph/sub/b.png", "ph/sub/deep/c.png", "ph/sub/up/a.png",
        "ph/sub2/b.png",
    ]  # fmt: skip
    assert len(glob.glob("ph/sub/up/sub/up/*.png")) == 1  # Python's glob would go on down


@pytest.mark.parametrize("target", ["/", "../.."])
def test_a_link_to_a_folder_holding_the_search_is_not_followed_and_named(tree, target):
    """A tryer's link to / made ** search the whole file system (it ended, with no word)."""
    os.symlink(target, "ph/sub/all")
    with pytest.warns(UserWarning) as caught:
        found = sorted(glob_once("ph/**/*.png"))
    assert found == ["ph/[odd]/e.png", "ph/a.png", "ph/sub/b.png", "ph/sub/deep/c.png"]
    real = os.path.realpath(os.path.join("ph/sub", target))
    assert [str(w.message) for w in caught] == [
        f"batch 'ph/**/*.png': ph/sub/all (to {real}) not searched: a link to a folder that holds "
        "the folder searched (** would search all of it)"
    ]


def test_each_link_up_not_followed_is_named_with_its_folder(tree):
    """The warning named the first link and 'and 2 more', with the first one's folder alone."""
    for name, target in [("all", "/"), ("far", "../../.."), ("top", "../..")]:
        os.symlink(target, f"ph/sub/{name}")
    with pytest.warns(UserWarning) as caught:
        glob_once("ph/**/*.png")
    far, top = os.path.realpath(".."), os.path.realpath(".")
    assert [str(w.message) for w in caught] == [
        f"batch 'ph/**/*.png': ph/sub/all (to /), ph/sub/far (to {far}), ph/sub/top (to {top}) "
        "not searched: links to folders that hold the folder searched (** would search all of it)"
    ]


def test_a_link_to_a_folder_beside_the_search_is_followed(tree):
    (tree / "other").mkdir()
    (tree / "other" / "f.png").write_bytes(b"x")
    os.symlink(tree / "other", "ph/other")
    assert "ph/other/f.png" in glob_once("ph/**/*.png")


@pytest.mark.parametrize("link", ["alias", "Alias", "0link"])
def test_a_folder_is_searched_below_by_its_own_path_before_a_link_to_it(tree, link):
    """A link sorting before the folder it names (``ph/alias -> sub``) was searched below,
    so a file two levels down was named only through it (``ph/alias/deep/c.png``; found by
    TRY45)."""
    os.symlink("sub", f"ph/{link}")
    found = sorted(glob_once("ph/**/*.png"))
    assert "ph/sub/deep/c.png" in found and f"ph/{link}/deep/c.png" not in found
    assert f"ph/{link}/b.png" in found  # reached again: its files named, for the warning


def test_a_folder_is_searched_by_its_own_path_before_a_shorter_link_to_it(tree):
    """A link to a deeper folder (``ph/aa -> sub/deep``) was shorter, so the folder was
    searched below through it and its files named by it (found by TRY45b)."""
    os.symlink("sub/deep", "ph/aa")
    os.makedirs("ph/sub/deep/more")
    open("ph/sub/deep/more/f.png", "wb").close()
    found = sorted(glob_once("ph/**/*.png"))
    assert "ph/sub/deep/more/f.png" in found and "ph/aa/more/f.png" not in found
    assert "ph/aa/c.png" in found  # reached again: its files named, for the warning
