"""``shc view ROBOT``: one browser tab looking at a robot file (:mod:`shc_cli.view.server` serves it): the model in
its default stance, a slider per joint, the body pose, body clearance and stance scale, the workspaces and the
walkspace."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from shc_cli.errors import ShcError
from shc_cli.view import scene
from shc_cli.view.drawing import RobotDrawing, _default_tips, _outline_segments, _setup_scene

if TYPE_CHECKING:
    import viser

    from shc_cli.analysis.workspace import WorkspaceReport


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
