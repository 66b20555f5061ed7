"""Shared fixtures: the repository's folders and the bundled robots, loaded once per session."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest

from shc_cli.spec.loading import load_gait, load_robot
from shc_cli.spec.robot import Robot

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "golden"
EXPERIMENTS = ROOT / "docs" / "experiments"
sys.path.insert(0, str(EXPERIMENTS))  # the experiment scripts (a folder, not a package) import as modules in tests

IN_CI = os.environ.get("CI") == "true"
"""CI (``CI=true``, as .ci/run and CI services set it): a browser or GL test must run, not skip."""


def unless_missing(missing: bool, reason: str) -> pytest.MarkDecorator:
    """Skip a test whose tool (Chromium, offscreen OpenGL) is ``missing`` — except in CI, where it fails with
    ``reason`` instead, so a CI machine without the tool cannot pass by skipping."""
    if missing and IN_CI:
        return pytest.mark.missing_in_ci(reason)
    return pytest.mark.skipif(missing, reason=reason)


STARTED_FIRST = (
    "tests/test_docs_examples.py::test_readme_first_five_minutes_run_after_the_readme_set_up_in_a_fresh_clone",
)
"""Tests run before the others, in this order: the fast suite's longest (about a minute: the README's set-up in a fresh
clone, which builds its own environment and numba cache). Started first, the other worker runs the rest beside it —
and fills numba's cache meanwhile (:func:`_kernels_compiled_once`), which this worker then only loads — instead of a
worker starting it late and the suite waiting for it at the end."""


def _kernels_compiled_once(config: pytest.Config) -> None:
    """In a pytest-xdist worker, before its first test that may use shc's numba kernels, on a cold cache (a fresh
    clone, CI): the first worker to get here runs ``shc warmup`` (a process of its own: nothing imported into the
    tests' process) holding a lock; the other waits for it. Without it each worker, and each run-hw subprocess started
    before a kernel was cached, compiled what it first called — a real-time run compiling in its loop can miss its
    servos' replies. A cache filled before is left as it is (a kernel edited since compiles where it is first
    called, as without this)."""
    import fcntl
    import hashlib
    import subprocess
    import tempfile

    run = getattr(config, "workerinput", {}).get("testrunuid")
    if run is None or getattr(config, "_shc_kernels_warm", False):
        return
    config._shc_kernels_warm = True  # type: ignore[attr-defined]
    key = hashlib.sha1(str(ROOT).encode()).hexdigest()[:12]
    with open(Path(tempfile.gettempdir()) / f"shc-tests-{key}.warmup", "a+", encoding="utf-8") as stamp:
        fcntl.flock(stamp, fcntl.LOCK_EX)  # released when closed
        stamp.seek(0)
        cold = not any((ROOT / "shc_cli" / "model" / "__pycache__").glob("*.nbi"))
        if stamp.read() != run and cold:  # not done yet in this test run, and nothing cached
            subprocess.run([sys.executable, "-m", "shc_cli.cli", "warmup"], cwd=ROOT, capture_output=True,
                           timeout=900)
        stamp.seek(0)
        stamp.truncate()
        stamp.write(run)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    first = {nodeid: k for k, nodeid in enumerate(STARTED_FIRST)}
    items.sort(key=lambda item: first.get(item.nodeid, len(first)))  # stable: the rest keep their order


def pytest_runtest_setup(item: pytest.Item) -> None:
    missing = item.get_closest_marker("missing_in_ci")
    if missing is not None:
        pytest.fail(f"CI=true and {missing.args[0]}", pytrace=False)
    if item.nodeid not in STARTED_FIRST:
        _kernels_compiled_once(item.config)


@pytest.fixture(scope="session")
def bullet() -> Robot:
    """Bullet as OpenSHC configures it (robots/bullet_openshc.toml): the geometry of the real binary's recordings."""
    robot = load_robot(ROOT / "robots" / "bullet_openshc.toml").robot
    return robot


@pytest.fixture(scope="session")
def tripod():  # type: ignore[no-untyped-def]
    return load_gait("tripod").gait


@pytest.fixture
def field_csv(tmp_path: Path) -> Path:
    """A 12 × 8 field (8 lines along y, 12 columns along x), 0..0.2 m, with a 0.3 m spike at (+x end, +y edge)."""
    grid = np.random.default_rng(7).uniform(0.0, 0.2, size=(8, 12))
    grid[0, -1] = 0.3
    path = tmp_path / "field.csv"
    np.savetxt(path, grid, delimiter=",", fmt="%.6f")
    return path


def summary_problems(root: Path) -> list[str]:
    """Every ``summary.json`` under ``root`` checked against ``shc schema summary`` (a JSON Schema validator, not the
    model that wrote it): one line per file and problem."""
    import json

    import jsonschema

    from shc_cli.record.summary import summary_schema

    validator = jsonschema.Draft202012Validator(summary_schema())
    problems = []
    for file in sorted(root.rglob("summary.json")):
        try:
            data = json.loads(file.read_text(encoding="utf-8"))
        except (OSError, ValueError) as error:
            problems.append(f"{file}: {error}")
            continue
        problems += [f"{file}: {'.'.join(map(str, e.absolute_path)) or '(top)'}: {e.message}"
                     for e in validator.iter_errors(data)]
    return problems


@pytest.fixture(scope="session", autouse=True)
def summaries_follow_their_schema(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    """At the end of the session, every ``summary.json`` the tests wrote (under pytest's temporary folders) must
    validate against ``shc schema summary``; an error at the last test's teardown names each file that does not."""
    yield
    problems = summary_problems(tmp_path_factory.getbasetemp())
    assert not problems, "summary.json files that do not follow `shc schema summary`:\n" + "\n".join(problems)
