"""`shc view`: a robot or a run in the browser, served by viser.

viser (https://viser.studio) is a maintained Python library that serves a bundled three.js web client over a
websocket: no JavaScript build, no network access at run time (the client is inside the wheel), an API of scene
nodes (instanced meshes, lines, boxes) and GUI inputs (sliders, buttons, images) driven from Python. Each page
load is a new client and gets its own scene and controls, built from the target as it is on disk at that moment:
editing a robot file and reloading the page shows the change.

* A robot: the generated model (:mod:`shc_cli.view.scene`) in its default stance (OpenSHC's direct start-up), a
  slider per joint limited to the joint's range (a link whose joint is at a limit turns red), the body pose
  (x, y, z, roll, pitch, yaw; the feet stay where they stand, the legs follow by IK), body clearance and stance
  scale (the default stance recomputed), each leg's workspace (blue) and the walkspace around each stance
  position (green) on the ground.
* A run: the robot replayed from the log on the run's terrain, a timeline (play, pause, scrub, speed), feet
  green on the ground, the support polygon with the CoM (red) and ZMP (purple, simulate) projections, the actual
  (blue) and commanded (orange) body paths, and the run's power and contact plots with a cursor at the timeline's
  time.
"""

from __future__ import annotations

import contextlib
import io
import logging
import math
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from shc_cli.record.runread import RunLog
from shc_cli.view import meshes, scene
from shc_cli.view.drawing import RobotDrawing, _outline_segments, _rgb, _setup_scene
from shc_cli.view.robot_page import RobotPage

if TYPE_CHECKING:
    import viser


log = logging.getLogger(__name__)


def disconnect_errors() -> tuple[type[BaseException], ...]:
    """What updating a page raises when its browser tab has gone: the socket's errors (viser's websockets)."""
    from websockets.exceptions import ConnectionClosed

    return ConnectionError, ConnectionClosed

FRAME_RATE = 20.0
"""Playback updates per second."""
PLOT_RATE = 8.0
"""Plot cursor updates per second while playing."""
SPEEDS = ("0.25", "0.5", "1", "2", "4")


# -- a run -----------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class RunScene:
    """Everything a replay shows, computed once per run: poses, CoM and ZMP, paths, terrain, plot."""

    run: RunLog
    shape: scene.Shapes
    pose: scene.Poses
    com: np.ndarray
    zmp: np.ndarray
    commanded_path: np.ndarray
    terrain: scene.TerrainShapes
    plot: Any


def commanded_path(run: RunLog) -> np.ndarray:
    """The body path the controller asked for: its desired body-frame velocity integrated from the body's pose at
    the first RUNNING cycle, heading included, ``(K, 3)`` from that cycle on, at the logged heights [m]. The
    start-up, where nothing is commanded and the body only rises or settles, is left out: it drew a vertical line."""
    running = np.flatnonzero(run.running)
    start = int(running[0]) if len(running) else 0
    desired, rpy, position = run.desired[start:], run.rpy[start:], run.position[start:]
    dt = run.dt
    yaw = rpy[0, 2] + np.concatenate([[0.0], np.cumsum(desired[:-1, 2] * dt)])
    step = np.stack([desired[:, 0] * np.cos(yaw) - desired[:, 1] * np.sin(yaw),
                     desired[:, 0] * np.sin(yaw) + desired[:, 1] * np.cos(yaw)], axis=1) * dt
    xy = position[0, :2] + np.concatenate([np.zeros((1, 2)), np.cumsum(step[:-1], axis=0)])
    return np.column_stack([xy, position[:, 2]])


def run_scene(run: RunLog) -> RunScene:
    """Precompute a replay of ``run``."""
    from shc_cli.analysis.metrics import feet_and_com

    shape = scene.shapes(run.robot)
    pose = scene.poses(shape, run.joints, run.position, run.rpy)
    rows = np.arange(len(run.t))
    _, com = feet_and_com(run, rows)
    zmp = np.full((len(rows), 2), np.nan)
    if run.foot_force is not None:
        weights = np.where(run.contact, np.maximum(run.foot_force, 0.0), 0.0)
        total = weights.sum(axis=1)
        ok = total > 0.0
        zmp[ok] = (pose.feet[ok, :, :2] * weights[ok, :, None]).sum(axis=1) / total[ok, None]  # ATHENA eq. 32
    terrain = scene.terrain_shapes(run.summary, run.robot)
    return RunScene(run, shape, pose, com, zmp, commanded_path(run), terrain, PlotImage(run))


class PlotImage:
    """The run's power and contact plots as an image, with a cursor line drawn at a time."""

    def __init__(self, run: RunLog) -> None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        t = run.t
        panels = 2 if run.power is not None else 1
        figure, axes = plt.subplots(panels, 1, figsize=(4.2, 1.3 + 1.2 * panels), dpi=100, sharex=True,
                                    squeeze=False)
        axes = axes[:, 0]
        if run.power is not None:
            axes[0].plot(t, run.power, lw=0.7, color="tab:blue")
            axes[0].set_ylabel("power [W]", fontsize=8)
        ax = axes[-1]
        for i, _leg in enumerate(run.legs):
            down = run.contact[:, i]
            edges = np.flatnonzero(np.diff(np.concatenate([[0], down.astype(int), [0]])))
            spans = [(t[a], t[min(b, len(t) - 1)] - t[a]) for a, b in zip(edges[::2], edges[1::2], strict=True)]
            ax.broken_barh(spans, (i - 0.4, 0.8), color="tab:green")
        ax.set_yticks(range(len(run.legs)), run.legs, fontsize=7)
        ax.set_ylabel("contact", fontsize=8)
        ax.set_xlabel("time [s]", fontsize=8)
        for a in axes:
            a.tick_params(labelsize=7)
            a.set_xlim(t[0], t[-1])
        figure.tight_layout()
        figure.canvas.draw()
        self.image = np.asarray(figure.canvas.buffer_rgba())[..., :3].copy()  # type: ignore[attr-defined]
        height = self.image.shape[0]
        (x0, _), (x1, _) = axes[0].transData.transform([(t[0], 0.0), (t[-1], 0.0)])
        top = height - axes[0].get_window_extent().y1
        bottom = height - axes[-1].get_window_extent().y0
        self.x0, self.x1, self.t0, self.t1 = float(x0), float(x1), float(t[0]), float(t[-1])
        self.top, self.bottom = int(max(0, top)), int(min(height, bottom))
        plt.close(figure)

    def at(self, time_s: float) -> np.ndarray:
        """The plots with a red cursor at ``time_s``."""
        image = self.image.copy()
        share = 0.0 if self.t1 <= self.t0 else (time_s - self.t0) / (self.t1 - self.t0)
        x = round(self.x0 + share * (self.x1 - self.x0))
        image[self.top:self.bottom, max(0, x - 1):x + 1] = (220, 30, 30)
        return image


class RunPage:
    """One browser tab replaying a run; ``live``: a run in progress, which :meth:`refresh` extends as it is written
    (``shc view RUN --follow``: :mod:`shc_cli.view.follow`)."""

    def __init__(self, client: viser.ClientHandle, data: RunScene, live: bool = False) -> None:
        self.client = client
        self.data = data
        self.live = live
        run = data.run
        gui, api = client.gui, client.scene
        reach = max(math.hypot(leg.stance.x, leg.stance.y) for leg in run.robot.legs.values())
        _setup_scene(client, np.array([run.position[0, 0], run.position[0, 1], 0.0]), 2.5 * reach + 0.3)
        self._terrain(api)
        self.drawing = RobotDrawing(api, data.shape)
        self._paths()
        self.polygon: Any = None
        self.com = api.add_icosphere("/com", radius=0.012, color=(220, 30, 30))
        self.zmp = api.add_icosphere("/zmp", radius=0.012, color=(150, 40, 200), visible=False)
        duration = float(run.t[-1])
        self.header = gui.add_markdown(self._header(finished=not live))
        self.timeline = gui.add_slider("time [s]", min=float(run.t[0]), max=duration, step=run.dt,
                                       initial_value=duration if live else float(run.t[0]))
        self.newest = gui.add_checkbox("show the newest row", initial_value=True) if live else None
        buttons = gui.add_button_group("playback", ("Play", "Pause"))
        self.speed = gui.add_dropdown("speed", SPEEDS, initial_value="1")
        self.follow = gui.add_checkbox("camera follows the body", initial_value=True)  # else it walks out of view
        self.status = gui.add_markdown("")
        self.plot = gui.add_image(data.plot.at(float(run.t[0])), label="power and contacts", format="jpeg",
                                  jpeg_quality=85)
        self.playing = False
        self.alive = True
        self.lock = threading.Lock()  # the playback thread and the browser's scrubbing both redraw
        self._last_plot = 0.0
        buttons.on_click(lambda event: self._button(event.target.value))
        self.timeline.on_update(lambda _event: self._show())
        self._show(force_plot=True)
        threading.Thread(target=self._play, name="shc-view-play", daemon=True).start()

    def _header(self, finished: bool) -> str:
        run, data = self.data.run, self.data
        summary, duration = run.summary, float(run.t[-1])
        text = (f"**{run.robot.name}** / {summary.gait or ''} — {run.kind} run `{run.path.name}`, {duration:.1f} s on "
                f"{data.terrain.text}.  \nBlue: body path; orange: commanded path; red: CoM; purple: ZMP; green feet: "
                "on the ground.")
        if not finished:
            return text + f"  \n**Following the run as it is written** ({duration:.1f} s so far)."
        return text + ("" if run.complete else f"  \n**Partial run**: stopped by {summary.stop_reason} after "
                                                f"{duration:.1f} s.")

    def _paths(self) -> None:
        """The body's path (blue) and the commanded path (orange), at most 800 segments each."""
        api, data = self.client.scene, self.data
        path = data.run.position.astype(np.float32)
        api.add_line_segments("/path/actual", _outline_segments(path[:: max(1, len(path) // 800)]),
                              (40, 90, 220), thickness=0.004)
        command = data.commanded_path.astype(np.float32)
        api.add_line_segments("/path/commanded", _outline_segments(command[:: max(1, len(command) // 800)]),
                              (240, 140, 20), thickness=0.004)

    def refresh(self, data: RunScene, finished: bool) -> None:
        """The run has grown (or ``finished``): extend the timeline and the paths; show the newest row unless the
        user turned that off (then the time shown stays)."""
        with self.lock:
            self.data = data
            self.timeline.max = float(data.run.t[-1])
            self._paths()
            self.header.content = self._header(finished)
        if self.newest is not None and self.newest.value and not self.playing:
            self.timeline.value = float(data.run.t[-1])  # type: ignore[misc]  # viser hides the setter; its update callback draws the row
        else:
            self._show(force_plot=True)
        if finished and self.newest is not None:
            self.newest.visible = False

    def _terrain(self, api: viser.SceneApi) -> None:
        if self.data.terrain.mesh is not None:
            vertices, faces = self.data.terrain.mesh
            api.add_mesh_simple("/heightfield", vertices.astype(np.float32), faces, color=_rgb(scene.TERRAIN_RGB),
                                side="double", position=(0.0, 0.0, 0.0005))
        boxes = self.data.terrain.boxes
        if not boxes:
            return
        vertices, faces = meshes.box()
        wxyz = scene.rpy_quaternion(np.array([[0.0, b.pitch, 0.0] for b in boxes])).astype(np.float32)
        api.add_batched_meshes_simple(
            "/terrain", vertices, faces, wxyz, np.array([b.centre for b in boxes], dtype=np.float32),
            batched_scales=np.array([b.size for b in boxes], dtype=np.float32),
            batched_colors=np.array([_rgb(b.rgb) for b in boxes], dtype=np.uint8), side="double")

    def _button(self, value: str) -> None:
        if value == "Play":
            run = self.data.run
            if self.timeline.value >= run.t[-1] - run.dt / 2:
                self.timeline.value = float(run.t[0])  # type: ignore[misc]  # viser hides the value setter
            self.playing = True
        else:
            self.playing = False
            self._show(force_plot=True)

    def _play(self) -> None:
        period = 1.0 / FRAME_RATE
        run = self.data.run
        while self.alive:
            time.sleep(period)
            if not self.playing:
                continue
            try:
                step = float(self.speed.value) * period
                value = min(float(self.timeline.value) + step, float(run.t[-1]))
                self.timeline.value = value  # type: ignore[misc]  # viser hides the value setter
                if value >= run.t[-1]:
                    self.playing = False
            except disconnect_errors():  # the tab went away before its disconnect callback stopped this thread
                self.alive = False
            except Exception:  # a bug, not a closed tab: stop the playback and say why
                log.exception("shc view: playback of %s stopped", run.path)
                self.alive = False

    def _show(self, force_plot: bool = False) -> None:
        with self.lock:
            self._draw(force_plot)

    def _draw(self, force_plot: bool) -> None:
        data, run = self.data, self.data.run
        value = float(self.timeline.value)
        row = int(np.clip(np.searchsorted(run.t, value + 1e-9, side="right") - 1, 0, len(run.t) - 1))
        contact = run.contact[row]
        api = self.client.scene
        with self.client.atomic():
            self.drawing.show(data.pose, row, contact)
            feet = data.pose.feet[row]
            ground = float(np.min(feet[:, 2])) if contact.any() else 0.0
            if contact.any():
                from shc_cli.analysis.metrics import support_polygon

                hull = support_polygon(feet[contact, :2])
                if len(hull) >= 2:
                    closed = np.vstack([hull, hull[:1]])
                    points = np.column_stack([closed, np.full(len(closed), ground + 0.003)])
                    self.polygon = api.add_line_segments("/support", _outline_segments(points), (220, 30, 30),
                                                         thickness=0.003)
            elif self.polygon is not None:
                self.polygon.visible = False
            self.com.position = (float(data.com[row, 0]), float(data.com[row, 1]), ground + 0.004)
            if np.isfinite(data.zmp[row]).all():
                self.zmp.position = (float(data.zmp[row, 0]), float(data.zmp[row, 1]), ground + 0.004)
                self.zmp.visible = True
            else:
                self.zmp.visible = False
            state = run.states[row, 0] if run.states is not None else ""
            commanded = float(np.hypot(run.desired[row, 0], run.desired[row, 1]))
            power = f", {run.power[row]:.0f} W" if run.power is not None else ""
            self.status.content = (f"t = {run.t[row]:.2f} s — {state} / {run.walk_state[row]}, commanded "
                                   f"{commanded:.3f} m/s{power}")
        if self.follow.value:
            camera = self.client.camera
            target = np.array([run.position[row, 0], run.position[row, 1], 0.0])
            offset = np.asarray(camera.position) - np.asarray(camera.look_at)
            camera.look_at = tuple(target)
            camera.position = tuple(target + offset)
        now = time.monotonic()
        if force_plot or not self.playing or now - self._last_plot >= 1.0 / PLOT_RATE:
            self._last_plot = now
            self.plot.image = data.plot.at(float(run.t[row]))

    def close(self) -> None:
        self.alive = False


# -- the server ------------------------------------------------------------------------------------------------


def is_run(target: str) -> bool:
    """A run directory or a bag (not a robot name or file)."""
    path = Path(target)
    return path.is_dir() or path.suffix == ".bag"


def check_target(target: str) -> None:
    """A missing path that is not a robot (a folder path, not ``*.toml``) is a missing run: say so (one line)
    instead of "no such robot file"."""
    path = Path(target)
    if not path.exists() and path.suffix != ".toml" and (len(path.parts) > 1 or path.suffix == ".bag"):
        from shc_cli.errors import NotFoundError

        raise NotFoundError(f"{target}: no such run directory or bag (give a run directory written by shc plan, "
                            "simulate or run-hw, a bag, or a robot file or bundled robot name)")


def serve(target: str, host: str, port: int, follow: bool = False) -> None:
    """Serve ``target`` at ``http://host:port`` until Ctrl-C; ``follow``: a run in progress, followed as it is
    written (:mod:`shc_cli.view.follow`)."""
    follower = None
    if follow:
        from shc_cli.view.follow import Follower, run_paths

        follower = Follower(*run_paths(target), on_update=lambda run, finished: refresh(run, finished))
    else:
        check_target(target)
    try:
        import viser
    except ImportError as error:
        from shc_cli.errors import Issue, SpecError, install_hint

        raise SpecError([Issue(None, None, "view", f"viser is not installed ({error})",
                               install_hint())]) from None

    from shc_cli.domain.stored_run import open_run as read_run  # directories and bags
    from shc_cli.spec.loading import load_robot

    data: RunScene | None = None
    if follower is not None:
        data = run_scene(follower.first())
    elif is_run(target):
        data = run_scene(read_run(Path(target)))
        note = data.run.partial_note()
        if note:
            print(f"note: {note}", file=sys.stderr, flush=True)
    else:
        loaded = load_robot(target)  # a bad file fails now, with its one-line error and exit 2
        if loaded.robot is None:
            from shc_cli.errors import Issue, SpecError, install_hint

            raise SpecError([Issue(None, None, target, "does not load", "shc validate it")])
    quiet_closed_connections()  # a closed tab's last draw is not worth a warning
    with contextlib.redirect_stdout(io.StringIO()):  # viser's own banner: shc prints one line instead
        server = viser.ViserServer(host=host, port=port, label="shc view", verbose=False)
    pages: dict[int, RunPage | RobotPage] = {}

    def connect(client: viser.ClientHandle) -> None:
        live = follower is not None and not follower.finished
        pages[client.client_id] = RunPage(client, data, live) if data is not None else RobotPage(client, target)

    def refresh(run: RunLog, finished: bool) -> None:
        """The followed run has grown: every open page shows it (a page that went away meanwhile is skipped)."""
        nonlocal data
        data = run_scene(run)
        for page in list(pages.values()):
            if isinstance(page, RunPage):
                with contextlib.suppress(*disconnect_errors()):
                    page.refresh(data, finished)

    def disconnect(client: viser.ClientHandle) -> None:
        page = pages.pop(client.client_id, None)
        if isinstance(page, RunPage):
            page.close()

    server.on_client_connect(connect)
    server.on_client_disconnect(disconnect)
    if follower is not None:
        follower.start()
    try:  # the URL inside: a Ctrl-C right after it is printed still stops the server here
        print(f"shc view: http://{host}:{server.get_port()}  (Ctrl-C to stop)", flush=True)
        while True:
            time.sleep(0.5)
    except KeyboardInterrupt:
        pass
    finally:
        if follower is not None:
            follower.stop()
        for page in pages.values():
            if isinstance(page, RunPage):
                page.close()
        stop_within(server, STOP_WAIT_S)


def quiet_closed_connections() -> None:
    """Silence viser's "Queued a GuiUpdateMessage on a closed connection" warning: a page's last draw (the replay's
    playback, a robot page's workspace search) races the closing of its browser tab, and viser then warns about a
    message nobody will receive — nothing the user did wrong or can act on (it was printed when a tab closed)."""
    import warnings

    warnings.filterwarnings("ignore", message=r"Queued a \w+ on a closed connection")


STOP_WAIT_S = 0.5
"""How long Ctrl-C waits for viser's server to stop [s] before ``shc view`` leaves anyway."""


def stop_within(server: viser.ViserServer, seconds: float) -> None:
    """Stop ``server`` in a daemon thread, waiting at most ``seconds``, and silence its late warnings.

    viser's ``stop`` joins its event-loop thread for up to 6 s, and pages still being built or redrawn in its worker
    threads (a robot page's workspace search: seconds on a loaded machine) keep drawing into closed connections,
    each draw a "Queued a … on a closed connection" warning. Python's exit would then wait for those workers to
    finish every queued callback; ``shc view`` leaves at once instead (:func:`shc_cli.commands.view.run_view`).
    """
    quiet_closed_connections()
    stopper = threading.Thread(target=server.stop, name="shc-view-stop", daemon=True)
    stopper.start()
    stopper.join(timeout=seconds)

