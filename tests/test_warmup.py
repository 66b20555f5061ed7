"""``shc warmup`` (run by the README's set-up command) compiles every numba kernel the commands use, so the first
``shc simulate`` or ``shc workspace`` after an install compiles nothing (it was ≈ 6× slower than the second)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

SHC = [sys.executable, "-m", "shc_cli.cli"]


def _compiled(cache: Path) -> set[str]:
    """The compiled kernel versions in numba's cache."""
    return {str(path.relative_to(cache)) for path in cache.rglob("*.nbc")}


@pytest.mark.slow  # compiles every kernel from an empty cache (≈ 10 s alone, a minute on a loaded machine)
def test_after_warmup_simulate_and_workspace_compile_nothing(tmp_path: Path) -> None:
    cache = tmp_path / "numba-cache"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}  # an empty cache, as after a fresh install
    done = subprocess.run([*SHC, "warmup"], capture_output=True, text=True, env=env, timeout=900)
    assert done.returncode == 0 and "compiled and cached" in done.stdout, done.stderr
    assert "compiling shc's kernels" in done.stderr  # a cold cache says why this command is slow
    warmed = _compiled(cache)
    assert len(warmed) >= 15, warmed
    for args in (["simulate", "--duration", "1", "--out", str(tmp_path / "run"), "--no-plots"],
                 ["workspace", "bullet", "--json"]):
        done = subprocess.run([*SHC, *args], capture_output=True, text=True, env=env, timeout=900)
        assert done.returncode == 0 and "compiling" not in done.stderr, done.stderr
        assert _compiled(cache) == warmed, f"shc {args[0]} compiled {sorted(_compiled(cache) - warmed)}"
