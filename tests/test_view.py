"""``shc view`` in a real browser: Debian's headless Chromium driven by Playwright looks at the served page."""

from __future__ import annotations

import io
import json
import os
import shutil
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from .conftest import ROOT, unless_missing

CHROMIUM = shutil.which("chromium") or ("/usr/bin/chromium" if Path("/usr/bin/chromium").exists() else None)
try:
    import playwright.sync_api  # noqa: F401

    HAVE_PLAYWRIGHT = True
except ImportError:  # pragma: no cover - the test extra installs it
    HAVE_PLAYWRIGHT = False

needs_chromium = unless_missing(
    CHROMIUM is None or not HAVE_PLAYWRIGHT,
    reason="needs Debian's chromium and playwright: apt-get update && apt-get install -y chromium chromium-driver; "
           "python3 -m uv pip install --python .venv -e '.[test]'")

ARGS = ["--headless=new", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
        "--disable-component-update", "--disable-sync", "--no-first-run", "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader"]
VIEWPORT = {"width": 1100, "height": 760}
SCENE = (slice(80, 740), slice(0, 760))
"""The part of the screenshot showing the 3-D scene (left of the control panel, below the notifications)."""


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@contextmanager
def served(target: str, *options: str) -> Iterator[str]:
    """Start ``shc view TARGET [OPTIONS]`` and yield its URL; Ctrl-C (SIGINT) stops it, which must exit 0."""
    port = _free_port()
    process = subprocess.Popen([sys.executable, "-m", "shc_cli.cli", "view", target, "--port", str(port), *options],
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=ROOT,
                               env={**os.environ, "PYTHONUNBUFFERED": "1"})
    assert process.stdout is not None
    url = ""
    deadline = time.monotonic() + 120
    lines = []
    while time.monotonic() < deadline and not url:
        line = process.stdout.readline()
        if not line and process.poll() is not None:
            break
        lines.append(line)
        if line.startswith("shc view: http://127.0.0.1:"):
            url = line.split()[2]
    assert url, "".join(lines)
    try:
        yield url
    finally:
        _interrupt(process)


CTRL_C_EXIT_S = 3.0
"""How long ``shc view`` may take to exit after Ctrl-C [s]: a second, with room for a loaded machine's scheduling."""


def _interrupt(process: subprocess.Popen[str]) -> None:
    """Ctrl-C (SIGINT) ``process``: it must exit 0 within :data:`CTRL_C_EXIT_S`."""
    process.send_signal(2)
    try:
        code = process.wait(timeout=CTRL_C_EXIT_S)
    except subprocess.TimeoutExpired:
        process.kill()
        raise AssertionError(f"shc view still running {CTRL_C_EXIT_S} s after Ctrl-C") from None
    assert code == 0, "shc view did not exit cleanly on Ctrl-C"


def _shot(page: Any) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(page.screenshot())).convert("RGB"))[SCENE].astype(int)


def _robot_mask(image: np.ndarray) -> np.ndarray:
    """Pixels of the links' orange (``LINK_RGB`` 0.85, 0.55, 0.15 under the viewer's lights): red well above blue."""
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    return np.asarray((r - b > 70) & (r > 110) & (g > b))


def _robot_pixels(image: np.ndarray) -> int:
    return int(_robot_mask(image).sum())


def _robot_centre(image: np.ndarray) -> np.ndarray:
    """Mean (row, column) of the robot's pixels."""
    centre: np.ndarray = np.argwhere(_robot_mask(image)).mean(axis=0)
    return centre


def _settle(page: Any, seconds: float = 2.5) -> np.ndarray:
    """A screenshot once the robot is drawn (polled up to 60 s), after ``seconds`` more for the scene to settle."""
    deadline = time.monotonic() + 60.0
    while _robot_pixels(_shot(page)) < 500 and time.monotonic() < deadline:
        time.sleep(1.0)
    time.sleep(seconds)
    return _shot(page)


def _changed(page: Any, before: np.ndarray, pixels: int = 300, timeout: float = 30.0) -> np.ndarray:
    """The first screenshot (polled each second, up to ``timeout``) differing from ``before`` in ``pixels`` pixels,
    then one more second later (the last one taken if none does)."""
    deadline = time.monotonic() + timeout
    while True:
        time.sleep(1.0)
        image = _shot(page)
        if (np.abs(image - before).sum(axis=2) > 40).sum() > pixels or time.monotonic() > deadline:
            time.sleep(1.0)
            return _shot(page)


def _slider(page: Any, label: str) -> Any:
    """The keyboard-driven thumb of the viser slider labelled ``label``."""
    target = page.locator("label", has_text=label).first.get_attribute("for")
    return page.locator(f'[id="{target}"] [role=slider]').first


@pytest.fixture
def browser() -> Iterator[Any]:
    from playwright.sync_api import sync_playwright

    with sync_playwright() as driver:
        chromium = driver.chromium.launch(executable_path=CHROMIUM, args=ARGS, headless=True)
        try:
            yield chromium
        finally:
            chromium.close()


def _open(browser: Any, url: str, text: str) -> Any:
    page = browser.new_page(viewport=VIEWPORT)
    page.goto(url)
    page.get_by_text(text).first.wait_for(timeout=60_000)
    return page


@needs_chromium
@pytest.mark.slow  # a real browser (Chromium) on shc view
def test_view_robot_draws_it_and_a_joint_slider_moves_it(browser: Any) -> None:
    with served(str(ROOT / "robots" / "bullet.toml")) as url:
        page = _open(browser, url, "AR coxa")
        before = _settle(page, 4.0)
        assert _robot_pixels(before) > 500, "no robot drawn"
        thumb = _slider(page, "AR coxa")
        thumb.focus()
        thumb.press("End")  # the coxa to its upper limit: the leg swings and turns red
        after = _changed(page, before)
        changed = (np.abs(after - before).sum(axis=2) > 40).sum()
        assert changed > 300, f"moving the joint slider changed only {changed} pixels"
        r, g, b = after[..., 0], after[..., 1], after[..., 2]
        assert ((r > 150) & (g < 90) & (b < 90)).sum() > 50, "a joint at its limit is not coloured"


@pytest.fixture(scope="module")
def plan_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("view") / "plan"
    subprocess.run([sys.executable, "-m", "shc_cli.cli", "plan", "bullet", "--duration", "3", "--out", str(out),
                    "--no-plots"], check=True, capture_output=True, cwd=ROOT)
    return out


@needs_chromium
@pytest.mark.slow  # a real browser (Chromium) on shc view
def test_view_run_replays_and_the_timeline_moves_the_robot(plan_run: Path, browser: Any) -> None:
    with served(str(plan_run)) as url:
        page = _open(browser, url, "time [s]")
        start = _settle(page, 4.0)
        assert _robot_pixels(start) > 500, "no robot drawn"
        thumb = _slider(page, "time [s]")
        thumb.focus()
        thumb.press("End")  # scrub to the end of the run: the robot has walked on
        end = _changed(page, start)
        changed = (np.abs(end - start).sum(axis=2) > 40).sum()
        assert changed > 300, f"scrubbing the timeline changed only {changed} pixels"
        assert _robot_pixels(end) > 300
        moved = np.linalg.norm(_robot_centre(end) - _robot_centre(start))
        assert moved > 10.0, f"the robot moved only {moved:.1f} px"


def _shown_time(page: Any) -> float:
    """The time of the row the run page shows, from its status line ``t = 1.23 s — …`` [s]."""
    import re

    text = page.get_by_text(re.compile(r"t = [0-9.]+ s — ")).first.inner_text()
    return float(re.search(r"t = ([0-9.]+) s", text).group(1))  # type: ignore[union-attr]


@needs_chromium
@pytest.mark.slow  # a real browser (Chromium) on shc view, beside a real-time simulation
def test_view_follow_shows_a_simulation_while_it_runs(tmp_path: Path, browser: Any) -> None:
    """``shc view RUN --follow`` on a ``--realtime`` simulation in progress: the page shows the newest rows as they
    are written (the shown time advances with the wall clock and the robot moves), then the finished run."""
    run = tmp_path / "walk"
    sim = subprocess.Popen([sys.executable, "-m", "shc_cli.cli", "simulate", "--engine", "mujoco", "--realtime",
                            "--duration", "30", "--no-plots", "--out", str(run)], cwd=ROOT,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 120
        while not (run.with_name("walk.partial") / "log.csv").exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        with served(str(run), "--follow") as url:
            page = _open(browser, url, "Following the run as it is written")
            before = _settle(page, 1.0)
            first = _shown_time(page)
            time.sleep(5.0)
            later = _shown_time(page)
            assert sim.poll() is None, "the simulation ended before the page was checked"
            assert later > first + 3.0, (first, later)  # the newest row, about as fresh as the wall clock
            after = _shot(page)
            changed = (np.abs(after - before).sum(axis=2) > 40).sum()
            assert changed > 300, f"the followed robot changed only {changed} pixels"
            assert sim.wait(timeout=120) == 0
            deadline = time.monotonic() + 30
            while page.get_by_text("Following the run as it is written").count() and time.monotonic() < deadline:
                time.sleep(0.5)
            assert not page.get_by_text("Following the run as it is written").count(), "never shown as finished"
            assert _shown_time(page) == pytest.approx(float(json.loads((run / "summary.json").read_text())
                                                            ["sim_time_s"]) - 0.01, abs=0.011)  # the last row
    finally:
        if sim.poll() is None:
            sim.kill()
            sim.wait()


@needs_chromium
@pytest.mark.slow  # a real browser (Chromium) on shc view
def test_view_robot_reload_shows_the_edited_file(tmp_path: Path, browser: Any) -> None:
    robot = tmp_path / "mine.toml"
    text = (ROOT / "robots" / "bullet_openshc.toml").read_text(encoding="utf-8")  # OpenSHC's Bullet: 13.37 kg
    robot.write_text(text, encoding="utf-8")
    with served(str(robot)) as url:
        page = _open(browser, url, "AR coxa")
        assert page.get_by_text("13.37 kg").count() == 1
        before = _settle(page, 3.0)
        wide = text.replace("size = [0.6, 0.14, 0.101]", "size = [0.6, 0.40, 0.101]")
        wide = wide.replace("mass = 7.2", "mass = 9.2")
        assert wide != text
        robot.write_text(wide, encoding="utf-8")
        page.reload()
        page.get_by_text("15.37 kg").first.wait_for(timeout=60_000)  # the body's 2 kg more
        after = _settle(page, 3.0)
        assert _body_pixels(after) > _body_pixels(before) * 1.3, "the wider body is not drawn"


def _body_pixels(image: np.ndarray) -> int:
    """Pixels of the body's blue-grey (``BODY_RGB`` 0.35, 0.38, 0.42 under the viewer's lights)."""
    r, b = image[..., 0], image[..., 2]
    return int(((np.abs(r - 90) < 30) & (np.abs(b - 107) < 30) & (b >= r)).sum())


def test_view_of_something_unreadable_is_one_line(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    from .test_cli import run

    for target in ("no_such_robot", str(tmp_path)):
        code, out, err = run(["view", target, "--port", str(_free_port())], capsys, monkeypatch)
        assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err


@pytest.mark.slow  # shc view and a plan as subprocesses
def test_view_says_an_interrupted_run_is_partial(plan_run: Path, tmp_path: Path) -> None:
    """A run finished after Ctrl-C (``"complete": false``) opens in ``shc view`` with a note that it is partial."""
    import json

    pytest.importorskip("viser")
    partial = tmp_path / "partial"
    shutil.copytree(plan_run, partial)
    summary = json.loads((partial / "summary.json").read_text(encoding="utf-8"))
    summary.update(complete=False, stop_reason="SIGINT")
    (partial / "summary.json").write_text(json.dumps(summary), encoding="utf-8")
    process = subprocess.Popen([sys.executable, "-m", "shc_cli.cli", "view", str(partial), "--port", str(_free_port())],
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=ROOT,
                               env={**os.environ, "PYTHONUNBUFFERED": "1"})
    assert process.stdout is not None
    lines: list[str] = []
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            line = process.stdout.readline()
            if not line:
                break
            lines.append(line)
            if line.startswith("shc view: http://"):
                break
    finally:
        _interrupt(process)
    text = "".join(lines)
    assert "shc view: http://" in text, text
    assert "a partial run (stopped by SIGINT" in text, text


@pytest.mark.slow  # shc view and a plan as subprocesses
def test_view_leaves_at_once_on_ctrl_c_while_a_page_is_being_built() -> None:
    """Ctrl-C while a browser's robot page is still being built (its workspace search runs in viser's worker
    threads, seconds on a loaded machine): ``shc view`` exits 0 within a second or so, not when the page is done."""
    pytest.importorskip("viser")
    import asyncio

    import msgspec.msgpack
    import viser
    import websockets
    from viser import _messages

    with served(str(ROOT / "robots" / "bullet.toml")) as url:
        async def connect_then_interrupt() -> int:
            socket_url = url.replace("http://", "ws://")
            async with websockets.connect(socket_url, subprotocols=[f"viser-v{viser.__version__}"],  # type: ignore[list-item]
                                          max_size=None) as client:
                # viser counts a client as connected (and builds its page) at its first camera message
                camera = _messages.ViewerCameraMessage((1.0, 0.0, 0.0, 0.0), (1.0, 1.0, 1.0), 1.0, 0.01, 100.0, 600,
                                                       800, (0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
                await client.send(msgspec.msgpack.encode(camera.as_serializable_dict()))
                received = 0
                while received < 3:  # the page has begun to be built (scene messages arrive)
                    await asyncio.wait_for(client.recv(), 60.0)
                    received += 1
                return received

        assert asyncio.run(connect_then_interrupt()) == 3
