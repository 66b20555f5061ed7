"""Every file the CLI reads, fuzzed: seeded mutations of valid files, each run through ``shc`` in-process.

For each input kind a few valid seed files are mutated (:func:`mutate`: numbers swapped for NaN, infinities,
huge, negative or wrong-typed values; lines deleted, duplicated, swapped or cut; bytes flipped and junk inserted)
and handed to the command that reads that kind. Every case must end with exit 0, or exit 2 with only
``error: …`` lines that name the file, no traceback and no internal error (exit 1), and — when it fails — no output
directory or ``.partial`` left behind.

Adding a kind is one :class:`Kind` entry in :data:`KINDS`: its seed files, the ``shc`` arguments that read the
fuzzed file, and optionally companion files (``prepare``) and stubs for expensive work past the reading
(``stub``).

Set ``SHC_FUZZ_CASES`` to run more (or fewer) cases per kind than :data:`CASES`.
"""

from __future__ import annotations

import json
import os
import random
import re
import shutil
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from shc_cli.cli import main

from .conftest import ROOT

pytestmark = pytest.mark.slow  # the full fuzz: hundreds of mutated files through the CLI

CASES = int(os.environ.get("SHC_FUZZ_CASES", "200"))
"""Mutated files tried per kind."""

INTERESTING = ["nan", "inf", "-inf", "-1", "0", "1e308", "-1e308", "1e-320", "99999999999999999999", "0.5", "-0.0",
               '"x"', '""', "[]", "{}", "[1, 2]", "true", "", "1e400", "NaN", "0x10", "1_000"]
"""Values a number is replaced with (TOML- and CSV-valid or not)."""

# A quick robot for runs: the OpenSHC default hexapod with a 0.1 s start-up (a run is a few dozen cycles).
QUICK_ROBOT = 'extends = "openshc_default"\n\n[start_up]\ntime_to_start = 0.1\n'


# -- the mutator -------------------------------------------------------------------------------------------------


def mutate(data: bytes, rng: random.Random, binary: bool = False) -> bytes:
    """One to three random mutations of a file's bytes: text edits for text files, byte edits for binary ones."""
    for _ in range(rng.randint(1, 3)):
        data = (_mutate_bytes if binary or rng.random() < 0.1 else _mutate_text)(data, rng)
    return data


def _mutate_bytes(data: bytes, rng: random.Random) -> bytes:
    if not data:
        return bytes([rng.randrange(256)])
    where = rng.randrange(len(data))
    choice = rng.randrange(5)
    if choice == 0:  # flip some bytes
        out = bytearray(data)
        for _ in range(rng.randint(1, 8)):
            out[rng.randrange(len(out))] = rng.randrange(256)
        return bytes(out)
    if choice == 1:  # truncate
        return data[:where]
    if choice == 2:  # delete a chunk
        return data[:where] + data[where + rng.randint(1, 64):]
    if choice == 3:  # duplicate a chunk
        return data[:where] + data[where:where + rng.randint(1, 64)] + data[where:]
    return data[:where] + bytes(rng.randrange(256) for _ in range(rng.randint(1, 8))) + data[where:]


NUMBER = re.compile(rb"(?<![\w.])-?\d+(\.\d+)?([eE][-+]?\d+)?(?![\w.])")


def _mutate_text(data: bytes, rng: random.Random) -> bytes:
    lines = data.split(b"\n")
    choice = rng.randrange(9)
    if choice <= 2:  # a number becomes something interesting
        numbers = list(NUMBER.finditer(data))
        if numbers:
            hit = rng.choice(numbers)
            return data[:hit.start()] + rng.choice(INTERESTING).encode() + data[hit.end():]
    if choice == 3 and len(lines) > 1:  # delete a line
        del lines[rng.randrange(len(lines))]
        return b"\n".join(lines)
    if choice == 4:  # duplicate a line
        i = rng.randrange(len(lines))
        lines.insert(i, lines[i])
        return b"\n".join(lines)
    if choice == 5 and len(lines) > 1:  # swap two lines
        i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
        return b"\n".join(lines)
    if choice == 6 and data:  # cut the file short
        return data[:rng.randrange(len(data))]
    if choice == 7 and data:  # one character becomes a syntax character
        i = rng.randrange(len(data))
        return data[:i] + rng.choice([b"[", b"]", b"{", b"}", b"=", b",", b'"', b"'", b"\n", b"#", b".", b"-", b" ",
                                      b"\t", b"\xff", b"\x00"]) + data[i + 1:]
    words = list(re.finditer(rb"[A-Za-z_]{2,}", data))  # a word loses or gains a letter
    if words:
        hit = rng.choice(words)
        word = hit.group()
        word = word[:-1] if rng.random() < 0.5 else word + b"x"
        return data[:hit.start()] + word + data[hit.end():]
    return data + b"\n?"


# -- the kinds ---------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Kind:
    """One input kind: seed files, and how ``shc`` reads one.

    Attributes:
        name: test id.
        file: name of the fuzzed file in the case folder (several seeds may each pick their own: ``seeds`` maps
            file name → contents; a case mutates one of them).
        seeds: valid files, file name → bytes (all written to the case folder; one is mutated per case).
        argv: ``shc`` arguments for a case folder.
        binary: mutate as bytes (PNG, MCAP) instead of as text.
        prepare: writes companion files (a robot file, a run to analyse) into the case folder first.
        stub: replaces expensive work after the reading (a physics run), given pytest's monkeypatch.
        out: output directory (relative to the case folder) that must not exist after a failed case.
        mutable: the seed files a case may mutate (default: all of them).
        named_as: what else names the fuzzed file in an error (relative to the case folder): the source as given,
            e.g. a recording's prefix for its three files.
    """

    name: str
    seeds: Callable[[], dict[str, bytes]]
    argv: Callable[[Path], list[str]]
    binary: bool = False
    prepare: Callable[[Path], None] | None = None
    stub: Callable[[pytest.MonkeyPatch], None] | None = None
    out: str | None = None
    mutable: tuple[str, ...] = field(default_factory=tuple)
    named_as: str | None = None


REPLAY_CYCLES = 300
"""Cycles of the OpenSHC insectoid recording (golden/openshc-runs) in the replay seeds: start-up and settling."""


def _recording_seeds() -> dict[str, bytes]:
    """The recording's first cycles as the recorder's three files (their text; written gzipped, see ``_write``)."""
    import gzip

    seeds = {}
    for part in ("joints", "tips", "body"):
        with gzip.open(ROOT / "golden" / "openshc-runs" / f"insectoid_{part}.csv.gz", "rb") as source:
            seeds[f"rec_{part}.csv.gz"] = b"".join(next(source) for _ in range(REPLAY_CYCLES + 1))
    return seeds


def _replay_bag_seeds(ros1: bool) -> Callable[[], dict[str, bytes]]:
    def seeds() -> dict[str, bytes]:
        from shc_cli.replay.opening import open_source

        from .openshc_bags import write_openshc_bag

        folder = Path(os.environ["SHC_FUZZ_TMP"]) / f"replay-{'ros1' if ros1 else 'mcap'}"
        folder.mkdir(exist_ok=True)
        head = open_source(ROOT / "golden" / "openshc-runs" / "insectoid").head(REPLAY_CYCLES)
        path = write_openshc_bag(head, folder / ("rec.bag" if ros1 else "rec"), ros1=ros1)
        if ros1:
            return {"rec.bag": path.read_bytes()}
        return {f"rec/{p.relative_to(path)}": p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()}
    return seeds


def _urdf_seeds() -> dict[str, bytes]:
    from .urdf_robots import insect_leg, robot_urdf

    specs = [insect_leg(f"leg{i}", x, y, standing=True)
             for i, (x, y) in enumerate([(0.12, -0.08), (-0.12, -0.08), (-0.12, 0.08), (0.12, 0.08)])]
    return {"quad.urdf": robot_urdf(specs, name="quad").encode()}


def _write(target: Path, data: bytes) -> None:
    """A case's file: ``.gz`` files hold their (mutated) text compressed, as the recorder writes them."""
    import gzip

    target.parent.mkdir(parents=True, exist_ok=True)
    target.write_bytes(gzip.compress(data, mtime=0) if target.suffix == ".gz" else data)


def _quick_robot(folder: Path) -> None:
    (folder / "quick.toml").write_text(QUICK_ROBOT, encoding="utf-8")


def _plan_seeds() -> dict[str, bytes]:
    return {"plan.toml": b"""[[step]]
at = 0.0
velocity = [1.0, 0.0, 0.2]
[[step]]
cycle = 3
pose_velocity = [0, 0, 0.5, 0, 0, 0]
[[step]]
at = 0.08
pose_velocity = [0, 0, 0, 0, 0, 0]
pose_reset = "all"
parameters = { step_frequency = 1.5, swing_height = 0.06 }
[[step]]
at = 0.1
gait = "wave"
cruise = true
[[step]]
at = 0.12
velocity = [0, 0, 0]
leg_toggle = "AR"
[[step]]
at = 0.14
tip_velocity = { AR = [0, 0, 0.5] }
[[step]]
at = 0.16
state = "ready"
"""}


def _csv_seeds() -> dict[str, bytes]:
    return {"cmds.csv": b"cycle,vx,vy,wz\n0,1,0,0\n2,0.5,0.5,0\n4,0,0,0.3\n6,-1,0,0\n8,0,0,0\n"}


def _sweep_seeds() -> dict[str, bytes]:
    return {"sweep.toml": b"""name = "fuzz"
description = "every kind of key"
duration = 3.0

[[grid]]
robot = ["bullet", "bullet_mammalian"]
gait = ["tripod", "bipod"]
"walker.step_frequency" = [0.8, 1.1]

[[grid]]
"walker.body_clearance" = [0.2, 0.25]
stride_percent = [60, 100]
seed = [1, 2]

[fixed]
terrain = "flat"
"""}


def _stub_sweep(monkeypatch: pytest.MonkeyPatch) -> None:
    """No simulations: every point is an ``ok`` row at once (the reading and checking are what is fuzzed)."""
    from shc_cli.domain.sweeps import points

    def row(point: Any, out: str, *_: Any) -> dict[str, Any]:  # run_point's metrics and skip are not needed
        return {"index": point.index, "slug": point.slug, **point.values, "status": "ok", "error": ""}

    monkeypatch.setattr(points, "run_point", row)


STUDY_TRIALS = 2
"""Trials per study case (``--trials``: a mutated ``trials`` could ask for billions): enough for the sampler to draw
every dimension, tell a result and write the Pareto robot files and plots."""


def _study_seeds() -> dict[str, bytes]:
    """A study with every kind of key: each form of dimension, a constraint per form, every sampler key."""
    return {"study.toml": b"""name = "fuzz"
description = "every kind of key"
robot = "bullet"
terrain = "flat"
scenario = "WG"
engine = "pybullet"
duration = 0.3
skip = 0.1
seeds = [0, 1]
trials = 3

[fixed]
"start_up.time_to_start" = 0.5
friction = 0.9

[space]
gait = { choices = ["tripod", "bipod"] }
"walker.step_frequency" = { low = 0.8, high = 1.6, step = 0.1 }
"walker.swing_height" = { low = 0.05, high = 0.12, log = true }
stride_percent = { low = 50, high = 100 }

[objectives]
cot = "minimize"
mean_speed_mps = "maximize"

[constraints]
fell = false
mean_speed_mps = { min = 0.01, max = 5.0 }
joint_limit_fraction = { max = 0.05 }

[sampler]
name = "nsga2"
seed = 7
population = 2
"""}


def _stub_study_runs(monkeypatch: pytest.MonkeyPatch) -> None:
    """No simulations: every run of a trial is an ``ok`` row at once, its metrics made from the trial's values (the
    reading, checking, sampling, telling and writing of the results are what is fuzzed; tests/test_optimize.py runs
    real trials)."""
    from shc_cli.domain.sweeps import points

    def row(point: Any, out: str, metrics: tuple[str, ...] = (), skip: float = 0.0) -> dict[str, Any]:
        numbers = [float(v) for v in point.values.values() if isinstance(v, (int, float)) and not isinstance(v, bool)]
        base = 1.0 + abs(sum(numbers)) % 1.0
        return {"index": point.index, "slug": point.slug, **point.values, "status": "ok", "error": "", "fell": False,
                "max_tilt_rad": 0.0, "wall_time_s": 0.0, **{key: base * (k + 1) for k, key in enumerate(metrics)}}

    monkeypatch.setattr(points, "run_point", row)


def _pose_prepare(folder: Path) -> None:
    # this robot auto-poses with the set in fuzz_pose.toml (a path: a name would be looked up next to the gait)
    pose = f'\n[pose]\nauto = true\nauto_pose_type = "{folder}/fuzz_pose.toml"\n'
    (folder / "posing.toml").write_text(QUICK_ROBOT + pose, encoding="utf-8")


def _pose_seeds() -> dict[str, bytes]:
    return {"fuzz_pose.toml": (ROOT / "poses" / "openshc_tripod.toml").read_bytes()}


def _servo_seeds() -> dict[str, bytes]:
    text = (ROOT / "robots" / "bullet.toml").read_text(encoding="utf-8")
    table = text[text.index("[hardware]"):]
    table = table.replace('baud = 1000000', 'baud = 1000000\nreturn_delay_us = 0\ncurrent_limit_ma = 2000\n'
                          'ticks_per_revolution = 4096')
    table = table.replace("AR_coxa = { id = 11 }", 'AR_coxa = { id = 11, bus = 1, direction = -1, zero_ticks = 2048, '
                          'model = "XM430-W350" }')
    return {"servos.toml": f'extends = "bullet"\n\n{table}'.encode()}


def _heightfield_csv_seeds() -> dict[str, bytes]:
    rows = [",".join(f"{0.01 * ((i * j) % 7):.2f}" for j in range(8)) for i in range(8)]
    return {"field.csv": ("\n".join(rows) + "\n").encode()}


def _heightfield_png_seeds() -> dict[str, bytes]:
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    buffer = io.BytesIO()
    plt.imsave(buffer, (np.arange(64).reshape(8, 8) % 5) / 5.0, cmap="gray", format="png")
    return {"field.png": buffer.getvalue()}


class _TerrainBuilt(Exception):
    """Raised by the stubbed simulation once the fuzzed terrain was built (a valid file)."""


def _stub_simulation(monkeypatch: pytest.MonkeyPatch) -> None:
    """No robot and no physics run: build the parsed terrain in a DIRECT PyBullet client (what PyBullet makes of the
    height field is exercised) and stop with a marker error."""
    from shc_cli.backends import simulated
    from shc_cli.errors import ShcError

    def stub(robot: Any, options: Any) -> Any:  # the one place simulate builds its world
        import pybullet

        from shc_cli.backends.pybullet_.terrain_bodies import build_terrain

        client = pybullet.connect(pybullet.DIRECT)
        try:
            build_terrain(client, options.terrain, 0.9, 0.0, 0)
        finally:
            pybullet.disconnect(client)
        raise ShcError("fuzz: terrain accepted")

    monkeypatch.setattr(simulated, "open_world", stub)


RUNS: dict[str, Path] = {}


def _source_run(kind: str, tmp_root: Path) -> Path:
    """A short plan or simulate run of the quick robot, made once per session; cases mutate copies of it."""
    if kind in RUNS:
        return RUNS[kind]
    folder = tmp_root / f"source-{kind}"
    folder.mkdir(parents=True)
    _quick_robot(folder)
    out = folder / "run"
    if kind.startswith("bag-"):  # bag-mcap, bag-sqlite3, bag-ros1: the plan run exported
        plan = _source_run("plan", tmp_root)
        fmt = kind.removeprefix("bag-")
        out = folder / ("run.bag" if fmt == "ros1" else "run")
        code, _, err = _shc(["export", "bag", str(plan), "--format", fmt, "--out", str(out)])
    else:
        code, _, err = _shc([kind, str(folder / "quick.toml"), "--duration", "0.4", "--out", str(out), "--no-plots"])
    assert code == 0, err
    RUNS[kind] = out
    return out


def _run_seeds(kind: str) -> Callable[[], dict[str, bytes]]:
    def seeds() -> dict[str, bytes]:
        source = _source_run(kind, Path(os.environ["SHC_FUZZ_TMP"]))
        if source.is_file():  # a ROS 1 bag is one file
            return {source.name: source.read_bytes()}
        return {str(p.relative_to(source)): p.read_bytes() for p in sorted(source.rglob("*")) if p.is_file()}
    return seeds


def _files_under(folder: str, seeds: dict[str, bytes]) -> dict[str, bytes]:
    return {f"{folder}/{name}": data for name, data in seeds.items()}


KINDS = [
    Kind("plan-script", _plan_seeds, lambda d: ["plan", str(d / "quick.toml"), "--commands", str(d / "plan.toml"),
                                                "--duration", "0.2", "--out", str(d / "out"), "--no-plots"],
         prepare=_quick_robot, out="out"),
    Kind("timeline-csv", _csv_seeds, lambda d: ["plan", str(d / "quick.toml"), "--commands", str(d / "cmds.csv"),
                                                "--duration", "0.2", "--out", str(d / "out"), "--no-plots"],
         prepare=_quick_robot, out="out"),
    Kind("sweep", _sweep_seeds, lambda d: ["sweep", str(d / "sweep.toml"), "--workers", "1", "--out",
                                           str(d / "out")], stub=_stub_sweep, out="out"),
    Kind("pose-set", _pose_seeds, lambda d: ["plan", str(d / "posing.toml"), "--duration", "0.2", "--out",
                                             str(d / "out"), "--no-plots"],
         prepare=_pose_prepare, out="out"),
    Kind("servo-table", _servo_seeds, lambda d: ["validate", str(d / "servos.toml")]),
    Kind("heightfield-csv", _heightfield_csv_seeds,
         lambda d: ["simulate", "bullet", "--terrain", f"heightfield:{d / 'field.csv'},1,0.05", "--out",
                    str(d / "out"), "--no-plots"], stub=_stub_simulation, out="out"),
    Kind("heightfield-png", _heightfield_png_seeds,
         lambda d: ["simulate", "bullet", "--terrain", f"heightfield:{d / 'field.png'},0.1", "--out",
                    str(d / "out"), "--no-plots"], binary=True, stub=_stub_simulation, out="out"),
    Kind("plan-run", lambda: _files_under("run", _run_seeds("plan")()), lambda d: ["analyze", str(d / "run"),
                                                                                  "--json"]),
    Kind("simulate-run", lambda: _files_under("run", _run_seeds("simulate")()),
         lambda d: ["analyze", str(d / "run"), "--json"]),
    Kind("bag-mcap", lambda: _files_under("run", _run_seeds("bag-mcap")()),
         lambda d: ["analyze", str(d / "run"), "--json"]),
    Kind("bag-sqlite3", lambda: _files_under("run", _run_seeds("bag-sqlite3")()),
         lambda d: ["analyze", str(d / "run"), "--json"]),
    Kind("bag-ros1", _run_seeds("bag-ros1"), lambda d: ["analyze", str(d / "run.bag"), "--json"], binary=True),
    Kind("replay-recording", _recording_seeds, lambda d: ["replay", str(d / "rec"), "--robot", "bullet", "--json"],
         named_as="rec"),
    Kind("replay-bag-ros1", _replay_bag_seeds(ros1=True),
         lambda d: ["replay", str(d / "rec.bag"), "--robot", "bullet", "--json"], binary=True),
    Kind("replay-bag-mcap", _replay_bag_seeds(ros1=False),
         lambda d: ["replay", str(d / "rec"), "--robot", "bullet", "--json"]),
    Kind("study", _study_seeds, lambda d: ["optimize", str(d / "study.toml"), "--trials", str(STUDY_TRIALS),
                                           "--workers", "1", "--out", str(d / "out")],
         stub=_stub_study_runs, out="out"),
    Kind("urdf-import", _urdf_seeds, lambda d: ["import", "urdf", str(d / "quad.urdf"), "--out", str(d / "out")],
         out="out"),
]


# -- running and judging a case ----------------------------------------------------------------------------------


def _shc(argv: list[str]) -> tuple[int, str, str]:
    """``shc`` in-process through its ``main()`` (one-line errors, exit codes): (exit code, stdout, stderr).

    ``main()`` builds the click command of the one command it runs (``cli._app_for``), which is cheap enough per case.
    """
    import contextlib
    import io

    out, err = io.StringIO(), io.StringIO()
    saved = sys.argv
    sys.argv = ["shc", *argv]
    code = 0
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            main()
    except SystemExit as done:
        code = done.code if isinstance(done.code, int) else (0 if done.code is None else 1)
    finally:
        sys.argv = saved
    return code, out.getvalue(), err.getvalue()


def judge(code: int, stdout: str, stderr: str, fuzzed: str, folder: Path, out: str | None,
          named_as: str | None = None) -> str | None:
    """What is wrong with a case's outcome, or None."""
    if "Traceback" in stdout + stderr or "internal error" in stderr or code not in (0, 2):
        lines = [line for line in stderr.splitlines() if line.strip()]
        return f"exit {code}: {lines[-1] if lines else stdout[-300:]}"
    if code == 0:
        return None
    lines = stderr.strip().splitlines()
    if not lines or not all(line.startswith("error: ") for line in lines):
        return f"not error lines: {stderr[:300]!r}"
    if "fuzz: terrain accepted" in stderr:
        return None
    names = [Path(fuzzed).name, Path(fuzzed).parts[0], *([str(folder / named_as)] if named_as else [])]
    if not any(name in stderr for name in names):
        return f"does not name {fuzzed}: {lines[0]}"
    if out is not None and ((folder / out).exists() or list(folder.glob("*.partial"))):
        return f"left output behind: {lines[0]}"
    return None


@pytest.mark.parametrize("kind", KINDS, ids=[k.name for k in KINDS])
def test_mutated_inputs_fail_in_one_line_without_traceback(kind: Kind, tmp_path_factory: pytest.TempPathFactory,
                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    root = tmp_path_factory.getbasetemp() / "fuzz"
    root.mkdir(exist_ok=True)
    monkeypatch.setenv("SHC_FUZZ_TMP", str(root))
    monkeypatch.setenv("COLUMNS", "200")
    if kind.stub is not None:
        kind.stub(monkeypatch)
    seeds = kind.seeds()
    names = [n for n in seeds if not kind.mutable or n in kind.mutable]
    rng = random.Random(f"shc-fuzz-{kind.name}")
    folder = tmp_path_factory.mktemp(f"{kind.name}-seed")  # the seeds as they are: valid, so accepted
    if kind.prepare is not None:
        kind.prepare(folder)
    for name, data in seeds.items():
        _write(folder / name, data)
    code, _, stderr = _shc(kind.argv(folder))
    assert code == 0 or "fuzz: terrain accepted" in stderr, f"{kind.name}: the unmutated seeds fail: {stderr}"
    failures: dict[str, str] = {}
    outcomes: dict[int | str, int] = {}
    for case in range(CASES):
        folder = tmp_path_factory.mktemp(kind.name, numbered=True)
        if kind.prepare is not None:
            kind.prepare(folder)
        fuzzed = rng.choice(names)
        for name, data in seeds.items():
            binary = kind.binary or name.endswith((".mcap", ".png", ".db3", ".bag"))
            _write(folder / name, mutate(data, rng, binary) if name == fuzzed else data)
        code, stdout, stderr = _shc(kind.argv(folder))
        accepted = code == 0 or "fuzz: terrain accepted" in stderr
        outcomes["accepted" if accepted else code] = outcomes.get("accepted" if accepted else code, 0) + 1
        problem = judge(code, stdout, stderr, fuzzed, folder, kind.out, kind.named_as)
        if problem is not None:
            failures.setdefault(re.sub(r"0x[0-9a-f]+|\d+", "#", problem)[:100], f"case {case} ({fuzzed}): {problem}")
        else:
            shutil.rmtree(folder, ignore_errors=True)
    report = {"kind": kind.name, "cases": CASES, "accepted": outcomes.get("accepted", 0),
              "refused": outcomes.get(2, 0), "problems": len(failures)}
    print(json.dumps(report))
    assert not failures, f"{kind.name}: {len(failures)} distinct problems:\n" + "\n".join(
        list(failures.values())[:30])
