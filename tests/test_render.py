"""``shc render`` and ``--video``: the frames written, decoded back and looked at."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from .conftest import ROOT, unless_missing
from .test_cli import run

pytestmark = pytest.mark.slow  # offscreen OpenGL rendering of runs (and subprocesses)

FPS = 5.0


def _has_offscreen_gl() -> bool:
    code = ("from shc_cli.backends.mujoco_.gl import choose_gl; choose_gl('egl'); import mujoco; "
            "r = mujoco.Renderer(mujoco.MjModel.from_xml_string('<mujoco/>'), 16, 16); r.close()")
    return subprocess.run([sys.executable, "-c", code], capture_output=True).returncode == 0


needs_gl = unless_missing(not _has_offscreen_gl(),
                         reason="needs offscreen OpenGL: apt-get update && apt-get install -y libosmesa6")


@pytest.fixture(scope="module")
def plan_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """OpenSHC's Bullet: its packed legs are in view from the first frame (the paper's arrangement A, the default
    robot, packs them under its body, where the fixed camera does not see them)."""
    out = tmp_path_factory.mktemp("render") / "plan"
    subprocess.run([sys.executable, "-m", "shc_cli.cli", "plan", "bullet_openshc", "--duration", "2", "--out", str(out),
                    "--no-plots"], check=True, capture_output=True, cwd=ROOT)
    return out


def _logged_span(run_dir: Path) -> float:
    """First to last logged time of a plan run, read from its joints.csv directly [s]."""
    lines = (run_dir / "joints.csv").read_text().splitlines()
    column = lines[0].split(",").index("t")
    return float(lines[-1].split(",")[column]) - float(lines[1].split(",")[column])


def _link_pixels(frame: np.ndarray) -> int:
    """Pixels of the links' orange (0.85, 0.55, 0.15 under the lights): red well above blue, green between."""
    r, g, b = (frame[..., i].astype(int) for i in range(3))
    return int(((r - b > 80) & (r > 100) & (g > b + 20) & (r > g)).sum())


def _mp4_frames(path: Path) -> list[np.ndarray]:
    import imageio_ffmpeg

    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    width, height = meta["size"]
    return [np.frombuffer(frame, dtype=np.uint8).reshape(height, width, 3) for frame in reader]


@needs_gl
def test_render_mp4_has_every_frame_the_robot_and_motion(plan_run: Path, tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                          monkeypatch) -> None:
    out = tmp_path / "walk.mp4"
    code, stdout, err = run(["render", str(plan_run), "--out", str(out), "--fps", str(FPS), "--size", "320x180",
                             "--camera", "fixed"], capsys, monkeypatch)
    assert (code, err) == (0, ""), err
    frames = _mp4_frames(out)
    expected = math.floor(_logged_span(plan_run) * FPS + 1e-9) + 1
    assert len(frames) == expected
    assert f"{expected} frames" in stdout
    assert frames[0].shape == (180, 320, 3)
    assert all(_link_pixels(frame) > 100 for frame in frames[::5]), "the robot's orange is missing"
    # packed at the start, walking at the end: a fixed camera sees the picture change
    assert np.abs(frames[0].astype(int) - frames[-1].astype(int)).mean() > 1.0
    steps = [np.abs(a.astype(int) - b.astype(int)).mean() for a, b in zip(frames[-10:], frames[-9:], strict=False)]
    assert min(steps) > 0.0, "consecutive frames of the walk are identical"
    assert not list(tmp_path.glob(".*partial*"))


@needs_gl
def test_render_gif_speed_and_top_camera(plan_run: Path, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    from PIL import GifImagePlugin, Image

    out = tmp_path / "walk.gif"
    code, _, err = run(["render", str(plan_run), "--out", str(out), "--fps", str(FPS), "--size", "240x160",
                        "--camera", "top", "--speed", "2"], capsys, monkeypatch)
    assert (code, err) == (0, ""), err
    with Image.open(out) as gif:
        assert isinstance(gif, GifImagePlugin.GifImageFile)
        assert gif.n_frames == math.floor(_logged_span(plan_run) * FPS / 2 + 1e-9) + 1
        assert gif.size == (240, 160)
        assert gif.info["duration"] == 200
        gif.seek(gif.n_frames - 1)
        assert _link_pixels(np.asarray(gif.convert("RGB"))) > 50


@needs_gl
def test_plan_video_renders_the_finished_run(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    out, video = tmp_path / "run", tmp_path / "run.gif"
    monkeypatch.setattr("shc_cli.commands.render.DEFAULTS", (5.0, "160x90", "follow", 1.0))
    code, stdout, err = run(["plan", "bullet", "--duration", "0.5", "--no-plots", "--out", str(out), "--video",
                             str(video)], capsys, monkeypatch)
    assert (code, err) == (0, ""), err
    assert video.exists() and f"wrote {video}" in stdout


@needs_gl
def test_simulate_video_renders_though_the_physics_imported_mujoco_without_opengl(tmp_path: Path) -> None:
    """The physics imports MuJoCo with GL disabled (PyOpenGL is 0.1 s of every simulation); ``simulate --video``
    renders in that same process: the frames still show the robot."""
    code = f"""
import sys
from pathlib import Path
from shc_cli.backends.mujoco_.world import import_mujoco
import_mujoco()
assert "OpenGL" not in sys.modules, "the physics imported PyOpenGL"
sys.argv = ["shc", "simulate", "--duration", "0.5", "--no-plots", "--out", r"{tmp_path / 'run'}",
            "--video", r"{tmp_path / 'run.gif'}"]
import shc_cli.commands.render as render
render.DEFAULTS = (5.0, "160x90", "fixed", 1.0)
from shc_cli.cli import main
main()
"""
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}  # a user's shell
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, env=env,
                          timeout=600)
    assert done.returncode == 0, done.stderr
    from PIL import GifImagePlugin, Image

    with Image.open(tmp_path / "run.gif") as gif:
        assert isinstance(gif, GifImagePlugin.GifImageFile)
        gif.seek(gif.n_frames - 1)
        assert _link_pixels(np.asarray(gif.convert("RGB"))) > 20


def test_bad_render_options_are_one_line(plan_run: Path, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    for argv, field in ((["--out", str(tmp_path / "a.avi")], "--out"),
                        (["--out", str(tmp_path / "a.mp4"), "--size", "big"], "--size"),
                        (["--out", str(tmp_path / "a.mp4"), "--camera", "drone"], "--camera"),
                        (["--out", str(tmp_path / "a.mp4"), "--fps", "0"], "--fps")):
        code, _, err = run(["render", str(plan_run), *argv], capsys, monkeypatch)
        assert code == 2 and len(err.strip().splitlines()) == 1 and field in err, err
    code, _, err = run(["plan", "bullet", "--video", str(tmp_path / "v.mov"), "--out", str(tmp_path / "r")],
                       capsys, monkeypatch)
    assert code == 2 and "--video" in err and not (tmp_path / "r").exists()
    assert not list(tmp_path.glob("a.*"))


@needs_gl
def test_render_reads_a_bag_as_the_run(plan_run: Path, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    bag = tmp_path / "bag"
    code, _, err = run(["export", "bag", str(plan_run), "--out", str(bag)], capsys, monkeypatch)
    assert code == 0, err
    out = tmp_path / "bag.gif"
    code, _, err = run(["render", str(bag), "--out", str(out), "--fps", "2", "--size", "64x48"], capsys,
                            monkeypatch)
    assert (code, err) == (0, ""), err
    from PIL import GifImagePlugin, Image

    with Image.open(out) as gif:
        assert isinstance(gif, GifImagePlugin.GifImageFile)
        assert gif.n_frames == math.floor(_logged_span(plan_run) * 2 + 1e-9) + 1
