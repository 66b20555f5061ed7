"""The scene nodes both ``shc view`` pages draw with (:mod:`shc_cli.view.server`): the robot model as instanced
meshes (:class:`RobotDrawing`), the ground, lights and camera, and line-segment helpers."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from shc_cli.view import meshes, scene

if TYPE_CHECKING:
    import viser

    from shc_cli.analysis.workspace import WorkspaceReport


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
