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
    warmed = _compiled(cache)
    assert len(warmed) >= 15, warmed
    for args in (["simulate", "--duration", "1", "--out", str(tmp_path / "run"), "--no-plots"],
                 ["workspace", "bullet", "--json"]):
        done = subprocess.run([*SHC, *args], capture_output=True, text=True, env=env, timeout=900)
        assert done.returncode == 0 and "compiling" not in done.stderr, done.stderr
        assert _compiled(cache) == warmed, f"shc {args[0]} compiled {sorted(_compiled(cache) - warmed)}"


def test_a_command_compiling_the_kernels_says_so_once_on_a_terminal(monkeypatch: pytest.MonkeyPatch,
                                                                    caplog: pytest.LogCaptureFixture) -> None:
    from types import SimpleNamespace

    from shc_cli.model import jit

    def compiling(module: str) -> SimpleNamespace:
        return SimpleNamespace(data={"dispatcher": SimpleNamespace(py_func=SimpleNamespace(__module__=module))})

    notice = jit._CompileNotice()
    terminal = SimpleNamespace(isatty=lambda: True, write=lambda text: len(text), flush=lambda: None)
    monkeypatch.setattr("sys.stderr", terminal)
    with caplog.at_level("INFO", logger="shc_cli"):
        notice.on_start(compiling("numpy.something"))  # not one of shc's kernels
        assert not caplog.records
        notice.on_start(compiling("shc_cli.control.stepping"))
        notice.on_start(compiling("shc_cli.model.kernels"))
    assert [r.getMessage() for r in caplog.records] == [
        "compiling shc's kernels into numba's cache (once per install, ≈ 10 s; `shc warmup` does it ahead)"]


def test_a_cached_kernel_loads_without_numbas_compiler_registries(tmp_path: Path) -> None:
    """Loading a cached kernel installs only numba's runtime, not the typing and lowering rules compiling needs
    (``numba.np.arraymath`` and SciPy's ``linalg``: 0.2 s of every command): the first process compiles (and
    installs them), the second loads the same kernel, which allocates (numba's runtime) and gives the same frames."""
    code = """
import sys
import numpy as np
from shc_cli.model.kernels import chain_frames
n = 3
args = [np.zeros(3), np.array([0.1, 0.2, 0.3]), np.array([0.0, -0.4, 0.5]), np.array([0.05, 0.1, 0.12]),
        np.array([1.5707963, 0.0, 0.0]), np.array([0.3, -0.2, 0.7]), np.empty((n + 1, 4, 4))]
print(repr(chain_frames(*args).round(12).tolist()))
print("numba.np.arraymath" in sys.modules, "scipy.linalg" in sys.modules)
"""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba-cache")}
    compiled, loaded = (subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                                       timeout=600) for _ in range(2))
    assert compiled.returncode == 0 and loaded.returncode == 0, compiled.stderr + loaded.stderr
    frames, registries = compiled.stdout.splitlines()
    assert registries == "True True"  # compiling installs them
    assert loaded.stdout.splitlines() == [frames, "False False"]


def test_a_failing_load_shortcut_falls_back_to_numbas_own_loader(tmp_path: Path) -> None:
    """Should a numba release change the internals the shortcut uses, the kernel still loads from the cache (numba's
    own loader, registries first) and gives the same frames — here the shortcut's runtime set-up is made to fail."""
    code = """
import sys
import numpy as np
from numba.core.runtime import nrt
if sys.argv[1] == "break":  # the shortcut's first step fails once; numba's own path may call it again
    original, calls = nrt.rtsys.initialize, []
    def broken(context):
        calls.append(context)
        if len(calls) == 1:
            raise AttributeError("changed in this numba")
        return original(context)
    nrt.rtsys.initialize = broken
from shc_cli.model.kernels import chain_frames
n = 3
args = [np.zeros(3), np.array([0.1, 0.2, 0.3]), np.array([0.0, -0.4, 0.5]), np.array([0.05, 0.1, 0.12]),
        np.array([1.5707963, 0.0, 0.0]), np.array([0.3, -0.2, 0.7]), np.empty((n + 1, 4, 4))]
print(repr(chain_frames(*args).round(12).tolist()))
print(len(chain_frames.stats.cache_hits))
"""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba-cache")}
    compiled, loaded = (subprocess.run([sys.executable, "-c", code, mode], capture_output=True, text=True, env=env,
                                       timeout=600) for mode in ("compile", "break"))
    assert compiled.returncode == 0 and loaded.returncode == 0, compiled.stderr + loaded.stderr
    assert loaded.stdout.splitlines() == [compiled.stdout.splitlines()[0], "1"]  # the same frames, from the cache


def test_numba_is_imported_without_scipy_and_pyyaml_unless_a_numba_config_file_is_there(tmp_path: Path) -> None:
    """numba imports SciPy only to check its version and PyYAML only to read a ``.numba_config.yaml`` in the working
    directory: shc's kernels import numba without them (shc_cli.model.jit), but with such a file numba reads it."""
    code = """
import sys
import shc_cli.model.jit
from numba.core import config
print("scipy" in sys.modules, "yaml" in sys.modules, config.COLOR_SCHEME)
"""
    plain, configured = tmp_path / "plain", tmp_path / "configured"
    plain.mkdir()
    configured.mkdir()
    (configured / ".numba_config.yaml").write_text("color_scheme: light_bg\n", encoding="utf-8")
    outputs = [subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=folder, timeout=120)
               for folder in (plain, configured)]
    assert all(output.returncode == 0 for output in outputs), outputs[0].stderr + outputs[1].stderr
    assert [output.stdout.strip() for output in outputs] == ["False False no_color", "False True light_bg"]
