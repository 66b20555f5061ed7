"""The lint and type gates: ``.ci/run`` runs ruff and ``mypy --strict shc_cli tests`` after the install and before
the tests, ``shc_cli`` ships ``py.typed``, and both gates pass on this checkout."""

from __future__ import annotations

import subprocess
import sys

import pytest

from .conftest import ROOT


def test_ci_runs_ruff_and_mypy_after_the_install_and_before_the_tests() -> None:
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()
    commands = [line.strip() for line in ci if line.strip() and not line.lstrip().startswith(("#", "echo"))]
    install = commands.index('bash -c "$install_command"')
    ruff = commands.index(".venv/bin/ruff check")
    mypy = commands.index(".venv/bin/mypy --strict shc_cli tests")
    tests = commands.index('bash -c "$pytest_command"')
    assert install < ruff < tests and install < mypy < tests


def test_shc_cli_says_it_is_typed() -> None:
    """PEP 561: a user's mypy reads shc_cli's annotations only when the package carries ``py.typed``."""
    assert (ROOT / "shc_cli" / "py.typed").is_file()


def test_ruff_passes() -> None:
    done = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache"], cwd=ROOT, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stdout[-3000:]


@pytest.mark.slow  # about a minute without mypy's cache
def test_mypy_strict_passes_on_shc_cli_and_the_tests() -> None:
    done = subprocess.run([sys.executable, "-m", "mypy", "--strict", "shc_cli", "tests"], cwd=ROOT,
                          capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stdout[-3000:]
