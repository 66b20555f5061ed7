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
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from shc_cli.errors import ShcError
from shc_cli.record.runread import RunLog
from shc_cli.view import meshes, scene

if TYPE_CHECKING:
    import viser

    from shc_cli.analysis.workspace import WorkspaceReport

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


def _rgb(colour: tuple[float, float, float]) -> tuple[int, int, int]:
    return (round(colour[0] * 255), round(colour[1] * 255), round(colour[2] * 255))


class RobotDrawing:
    """The model's shapes as scene nodes of one client: instanced link cylinders, joint and foot spheres, a body
    box; :meth:`show` moves them to one frame of a :class:`~shc_cli.view.scene.Poses`."""

    def __init__(self, api: viser.SceneApi, shape: scene.Shapes, name: str = "/robot") -> None:
        self.shape = shape
        real = np.argwhere(shape.link_real)
        self.rows, self.cols = real[:, 0], real[:, 1]
        count = len(self.rows)
        self.radius = shape.link_radius[self.rows, self.cols].astype(np.float32)
        unit = np.tile(np.array([1.0, 0.0, 0.0, 0.0], dtype=np.float32), (count, 1))
        zeros = np.zeros((count, 3), dtype=np.float32)
        cylinder, sphere = meshes.cylinder(), meshes.sphere()
        self.links = api.add_batched_meshes_simple(
            f"{name}/links", *cylinder, unit, zeros, batched_scales=np.ones((count, 3), dtype=np.float32),
            batched_colors=np.tile(np.array(_rgb(scene.LINK_RGB), dtype=np.uint8), (count, 1)), side="double")
        self.joints = api.add_batched_meshes_simple(
            f"{name}/joints", *sphere, unit, zeros, batched_scales=self.radius,
            batched_colors=_rgb(scene.LINK_RGB))
        legs = len(shape.legs)
        self.feet = api.add_batched_meshes_simple(
            f"{name}/feet", *sphere, unit[:legs], zeros[:legs],
            batched_scales=shape.foot_radius.astype(np.float32),
            batched_colors=np.tile(np.array(_rgb(scene.FOOT_RGB), dtype=np.uint8), (legs, 1)))
        self.body = api.add_frame(f"{name}/body", show_axes=False)
        api.add_box(f"{name}/body/box", color=_rgb(scene.BODY_RGB), dimensions=shape.body_size,
                    position=shape.body_com)

    def show(self, pose: scene.Poses, index: int, contact: np.ndarray | None = None,
             limits: np.ndarray | None = None) -> None:
        """Frame ``index`` of ``pose``; feet green where ``contact`` ``(L,)``, links red where ``limits`` ``(L, n)``."""
        origins = pose.origins[index]
        start = origins[self.rows, self.cols]
        end = origins[self.rows, self.cols + 1]
        length = np.linalg.norm(end - start, axis=1)
        scales = np.column_stack([self.radius, self.radius, length]).astype(np.float32)
        self.links.batched_positions = start.astype(np.float32)
        self.links.batched_wxyzs = scene.z_to(end - start).astype(np.float32)
        self.links.batched_scales = scales
        self.joints.batched_positions = start.astype(np.float32)
        self.feet.batched_positions = origins[:, -1].astype(np.float32)
        if contact is not None:
            colours = np.where(np.asarray(contact)[:, None], _rgb(scene.CONTACT_RGB), _rgb(scene.FOOT_RGB))
            self.feet.batched_colors = colours.astype(np.uint8)
        red = limits[self.rows, self.cols] if limits is not None else np.zeros(len(self.rows), dtype=bool)
        self.links.batched_colors = np.where(red[:, None], _rgb(scene.LIMIT_RGB),
                                             _rgb(scene.LINK_RGB)).astype(np.uint8)
        self.body.position = pose.body_position[index]
        self.body.wxyz = pose.body_quaternion[index]


def _default_tips(report: WorkspaceReport) -> np.ndarray:
    """Tip positions of a workspace report's default joints in base_link, ``(L, 3)`` [m]."""
    return np.asarray(scene.shapes(report.robot).chains.tips(report.default_joints))


def _outline_segments(points: np.ndarray) -> np.ndarray:
    """A polyline ``(K, 3)`` as line segments ``(K − 1, 2, 3)``."""
    return np.stack([points[:-1], points[1:]], axis=1).astype(np.float32)


def _setup_scene(client: viser.ClientHandle, target: np.ndarray, distance: float) -> None:
    """Ground grid, lights without the network HDRI, and the camera looking at ``target`` from ``distance`` [m]."""
    api = client.scene
    client.camera.up_direction = (0.0, 0.0, 1.0)
    client.camera.position = tuple(target + distance * np.array([0.75, -0.95, 0.6]))
    client.camera.look_at = tuple(target)
    api.set_up_direction("+z")
    api.configure_environment_map(None)  # the default HDRI would be fetched from the network
    api.configure_default_lights(True, cast_shadow=False)
    # the default lights come from above: vertical faces (legs, the body's sides, feet seen from the side) were
    # nearly black; a sky/ground hemisphere light gives them a base brightness from every direction
    api.add_light_hemisphere("/light/fill", sky_color=(255, 255, 255), ground_color=(150, 150, 150), intensity=1.2)
    api.add_grid("/ground", width=6.0, height=6.0, cell_size=0.1, section_size=0.5, plane="xy",
                 position=(0.0, 0.0, -0.0005))


# -- a robot ---------------------------------------------------------------------------------------------------


@dataclass
class _RobotState:
    robot: Any
    shape: scene.Shapes
    joints: np.ndarray
    pose: np.ndarray = field(default_factory=lambda: np.zeros(6))
    clearance: float = 0.0
    feet: np.ndarray | None = None
    updating: bool = False


class RobotPage:
    """One browser tab looking at a robot file."""

    def __init__(self, client: viser.ClientHandle, target: str) -> None:
        from shc_cli.spec.loading import load_robot

        self.client = client
        self.target = target
        gui, api = client.gui, client.scene
        try:
            loaded = load_robot(target)
        except ShcError as error:
            gui.add_markdown(f"**{target}** does not load:\n\n```\n{error}\n```\n\nFix the file and reload the page.")
            return
        if loaded.robot is None:
            lines = "\n".join(str(issue) for issue in loaded.issues) if hasattr(loaded, "issues") else ""
            gui.add_markdown(f"**{target}** does not load:\n\n```\n{lines}\n```\n\nFix the file and reload the page.")
            return
        robot = loaded.robot
        self.base_robot = robot
        reach = max(math.hypot(leg.stance.x, leg.stance.y) for leg in robot.legs.values())
        _setup_scene(client, np.array([0.0, 0.0, robot.walker.body_clearance / 2]), 2.2 * reach + 0.3)
        self.shape = scene.shapes(robot)
        self.drawing = RobotDrawing(api, self.shape)
        gui.add_markdown(f"**{robot.name}** — {len(robot.legs)} legs, {robot.total_mass():.2f} kg. "
                         "Edit the file and reload the page to see the change.")
        self.message = gui.add_markdown("")
        self.state = _RobotState(robot, self.shape, np.zeros((len(robot.legs), self.shape.chains.joints)))
        with gui.add_folder("Stance"):
            clearance = robot.walker.body_clearance
            self.clearance = gui.add_slider("clearance [m]", min=round(clearance * 0.4, 3),
                                            max=round(clearance * 1.6, 3), step=0.001, initial_value=clearance)
            self.stance = gui.add_slider("stance scale", min=0.7, max=1.3, step=0.01, initial_value=1.0)
            reset = gui.add_button("Default stance")
        with gui.add_folder("Body pose"):
            self.pose_inputs = [gui.add_slider(label, min=-limit, max=limit, step=step, initial_value=0.0)
                                for label, limit, step in (("x [m]", 0.1, 0.002), ("y [m]", 0.1, 0.002),
                                                           ("z [m]", 0.08, 0.002), ("roll [rad]", 0.4, 0.005),
                                                           ("pitch [rad]", 0.4, 0.005), ("yaw [rad]", 0.5, 0.005))]
        self.sliders: list[tuple[int, int, Any]] = []
        with gui.add_folder("Joints [rad]"):
            for i, (leg_id, leg) in enumerate(robot.legs.items()):
                with gui.add_folder(leg_id, expand_by_default=i == 0):
                    for k, (name, joint) in enumerate(leg.joints.items()):
                        slider = gui.add_slider(f"{leg_id} {name}", min=float(joint.min), max=float(joint.max),
                                                step=0.001, initial_value=float(np.clip(0.0, joint.min, joint.max)))
                        self.sliders.append((i, k, slider))
                        slider.on_update(lambda _event: self._joints_changed())
        self.workspace_nodes: list[viser.SceneNodeHandle] = []
        self.clearance.on_update(lambda _event: self._stance_changed())
        self.stance.on_update(lambda _event: self._stance_changed())
        reset.on_click(lambda _event: self._stance_changed())
        for control in self.pose_inputs:
            control.on_update(lambda _event: self._pose_changed())
        self._stance_changed()

    def _stance_changed(self) -> None:
        """New clearance or stance scale: the default stance, workspaces and walkspace again."""
        from shc_cli.analysis.workspace import analyse_workspace
        from shc_cli.spec.loading import load_gait

        base = self.base_robot
        scale = float(self.stance.value)
        legs = {leg_id: leg.model_copy(update={"stance": leg.stance.model_copy(
            update={"x": leg.stance.x * scale, "y": leg.stance.y * scale})}) for leg_id, leg in base.legs.items()}
        walker = base.walker.model_copy(update={"body_clearance": float(self.clearance.value)})
        robot = base.model_copy(update={"legs": legs, "walker": walker})
        try:
            gait = load_gait(robot.walker.gait).gait
            report = analyse_workspace(robot, gait)
        except Exception as error:  # an unreachable stance: say so on the page, keep the last good one
            self.message.content = f"Stance not computed: {type(error).__name__}: {error}"
            return
        reachable = np.linalg.norm(_default_tips(report) - report.identity_tips, axis=1) < 1e-3
        self.message.content = "" if reachable.all() else (
            "Stance out of reach for " + ", ".join(leg for leg, ok in zip(robot.legs, reachable, strict=True)
                                                   if not ok))
        state = self.state
        state.updating = True  # the pose sliders go back to 0 without moving the legs
        try:
            for control in self.pose_inputs:
                control.value = 0.0  # type: ignore[misc]  # viser hides the value setter
        finally:
            state.updating = False
        state.robot, state.clearance = robot, robot.walker.body_clearance
        state.joints = np.array(report.default_joints, dtype=float)
        state.pose = np.zeros(6)
        self._draw_workspaces(report)
        self._set_sliders(state.joints)
        self._redraw()
        state.feet = self._pose().feet[0].copy()

    def _draw_workspaces(self, report: WorkspaceReport) -> None:
        for node in self.workspace_nodes:
            node.remove()
        api = self.client.scene
        legs, walk = [], []
        for leg_id, leg in report.robot.legs.items():
            centre = (leg.stance.x, leg.stance.y)
            legs.append(_outline_segments(scene.workplane_outline(report.planes[leg_id], centre, 0.002)))
            walk.append(_outline_segments(scene.workplane_outline(report.walkspace, centre, 0.003)))
        self.workspace_nodes = [
            api.add_line_segments("/workspace/legs", np.concatenate(legs), (40, 90, 220), thickness=0.004),
            api.add_line_segments("/workspace/walkspace", np.concatenate(walk), (30, 160, 60), thickness=0.004),
        ]

    def _set_sliders(self, joints: np.ndarray) -> None:
        self.state.updating = True
        try:
            for i, k, slider in self.sliders:
                slider.value = float(np.clip(joints[i, k], slider.min, slider.max))
        finally:
            self.state.updating = False

    def _pose(self) -> scene.Poses:
        state = self.state
        x, y, z, roll, pitch, yaw = state.pose
        position = np.array([[x, y, state.clearance + z]])
        return scene.poses(self.shape, state.joints[None], position, np.array([[roll, pitch, yaw]]))

    def _redraw(self) -> None:
        state = self.state
        with self.client.atomic():
            self.drawing.show(self._pose(), 0, limits=scene.at_limit(self.shape, state.joints))

    def _joints_changed(self) -> None:
        state = self.state
        if state.updating:
            return
        for i, k, slider in self.sliders:
            state.joints[i, k] = float(slider.value)
        self._redraw()

    def _pose_changed(self) -> None:
        """The body moves, the feet stay: each leg's joints by IK to its foot in the new body frame."""
        from shc_cli.analysis.metrics import rotation_rpy
        from shc_cli.model.ik import solve

        state = self.state
        if state.feet is None or state.updating:
            return
        state.pose = np.array([float(c.value) for c in self.pose_inputs])
        x, y, z, roll, pitch, yaw = state.pose
        rotation = rotation_rpy(np.array([roll, pitch, yaw]))
        position = np.array([x, y, state.clearance + z])
        targets = (state.feet - position) @ rotation  # world → base_link: Rᵀ(p − position)
        q, _ = solve(self.shape.chains, state.joints, targets, tolerance=1e-5, max_steps=200)
        state.joints = np.clip(q, self.shape.chains.lower, self.shape.chains.upper)
        self._set_sliders(state.joints)
        self._redraw()


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

