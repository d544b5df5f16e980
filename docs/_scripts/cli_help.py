"""The command line reference's generated half: each command's ``--help``, as printed."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import mkdocs_gen_files


def _help(*args: str) -> str:
    env = {**os.environ, "COLUMNS": "88"}
    done = subprocess.run(
        [sys.executable, "-m", "graphvision", *args, "--help"],
        capture_output=True,
        text=True,
        env=env,
        check=True,
    )
    return done.stdout.rstrip()


def commands(top: str) -> list[str]:
    """The sub-commands listed in the top-level help (4-space indented names)."""
    section = top.split("positional arguments:", 1)[-1].split("options:", 1)[0]
    return re.findall(r"^    (\w[\w-]*)", section, flags=re.MULTILINE)


def generate() -> None:
    top = _help()
    lines = [
        "",
        "## Every command's help",
        "",
        "Printed by the installed command when this site was built.",
        "",
    ]
    lines += ["### graphvision", "", "```text", top, "```", ""]
    for command in commands(top):
        lines += [f"### graphvision {command}", "", "```text", _help(command), "```", ""]
    with mkdocs_gen_files.open("reference/cli.md", "a") as out:
        out.write("\n".join(lines))
