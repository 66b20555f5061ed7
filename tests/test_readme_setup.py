"""The README's two set-up commands, taken from README.md itself, work in a fresh clone in either order and again.

A fresh CI machine only ever runs the test command once on a new clone; people run the main-job command, then the
test command (or the other way round, or one twice). Each command runs verbatim through ``bash -c`` except that the
test command's pytest is pointed at one quick test (running the whole suite inside the suite would take minutes);
the second install of a clone is quick because it reuses ``.venv`` and uv's cache (about 1–2 min in all).
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from .conftest import ROOT

ONE_TEST = " -p no:cacheprovider tests/test_cli.py::test_version"
"""Appended to the README's ``pytest -q``: the selection that stands in for the whole suite."""


def setup_commands(readme: str) -> tuple[str, str]:
    """The main-job and the test command: the shell blocks of the README's Set-up section, in that order."""
    section = readme.split("## Set-up", 1)[1].split("\n## ", 1)[0]
    blocks = [b.strip() for b in re.findall(r"```sh\n(.*?)```", section, re.S)]
    main = [b for b in blocks if "shc workspace" in b]
    test = [b for b in blocks if "pytest" in b]
    assert len(main) == 1 and len(test) == 1, f"expected one main-job and one test command in Set-up: {blocks}"
    return main[0], test[0]


def test_the_readme_has_one_line_commands_and_ci_runs_the_readme_test_command() -> None:
    main, test = setup_commands((ROOT / "README.md").read_text(encoding="utf-8"))
    for command in (main, test):
        assert "\n" not in command
        assert "--allow-existing" in command  # a second run must not stop at "A virtual environment already exists"
        assert command.startswith("python3 -m pip install")  # only python3 and its pip are assumed
    assert test.endswith("pytest -q -n auto")  # the fast suite (pyproject: -m "not slow") on every core
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert "README.md" in ci and "pytest" in ci  # .ci/run takes its test command from the README


def _run(command: str, clone: Path) -> None:
    done = subprocess.run(["bash", "-c", command], cwd=clone, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, f"{command}\nexit {done.returncode}\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}"


@pytest.mark.skipif(shutil.which("git") is None or not (ROOT / ".git").exists(),
                    reason="needs git and a git checkout to clone")
@pytest.mark.slow  # two or three installs in a clone; the fast suite runs the set-up once (tests/test_docs_examples.py)
@pytest.mark.parametrize("order", ["main, test", "test, main, main"])
def test_readme_setup_commands_work_in_either_order_and_again(order: str, tmp_path: Path) -> None:
    main, test = setup_commands((ROOT / "README.md").read_text(encoding="utf-8"))
    clone = tmp_path / "clone"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True, timeout=120)
    commands = {"main": main, "test": test + ONE_TEST}
    for name in order.split(", "):
        _run(commands[name], clone)
    assert (clone / "runs" / "workspace" / "limits.csv").is_file()
    assert (clone / ".venv" / "bin" / "shc").is_file()
