"""`shc render`: a run replayed headless into an MP4 or a GIF.

The scene (:mod:`shc_cli.view.scene`: the generated model's body box, link capsules and foot spheres, and the
run's terrain) is built as a MuJoCo model of motion-capture bodies — nothing is simulated, each frame only places
the bodies where the log says they were — and drawn by MuJoCo's offscreen OpenGL renderer through OSMesa
(software, no display or GPU; ``libosmesa6``) or EGL, without anti-aliasing or shadows (each doubles the
CPU time of a software frame). Measured against PyBullet's TinyRenderer on the same 960×540 frame: 24 ms against
252 ms of CPU per frame (docs/performance.md). Time, commanded and measured speed and the
walk state are written over each frame with Pillow. MP4 is encoded by the ffmpeg binary that ``imageio-ffmpeg``
ships in its wheel (H.264, yuv420p), GIF by Pillow. The output is written beside its final name and moved into
place when complete.
"""

from __future__ import annotations

import math
import os
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from shc_cli.errors import Issue, SpecError, install_hint
from shc_cli.record.runread import RunLog
from shc_cli.view import scene

CAMERAS = ("follow", "fixed", "top")
SPEED_WINDOW_S = 0.5
"""The measured speed is the body's horizontal displacement over this window, centred on the frame [s]."""


@dataclass(frozen=True)
class RenderOptions:
    """What `shc render` draws: frames per second of the video, size [px], camera, playback speed (× real time)."""

    fps: float = 25.0
    width: int = 960
    height: int = 540
    camera: str = "follow"
    speed: float = 1.0


@dataclass(frozen=True)
class RenderResult:
    """A finished video: its path, frame count and wall time split into drawing and encoding [s]."""

    path: Path
    frames: int
    draw_s: float
    encode_s: float


def parse_size(text: str) -> tuple[int, int]:
    """``WxH`` → (width, height) in pixels; one-line error otherwise."""
    width, _, height = text.lower().partition("x")
    try:
        w, h = int(width), int(height)
    except ValueError:
        w = h = 0
    if not (16 <= w <= 4096 and 16 <= h <= 4096):
        raise SpecError([Issue(None, None, "--size", f"'{text}' is not WIDTHxHEIGHT in pixels (16–4096)",
                               "e.g. --size 960x540")])
    return w, h


def check_options(out: Path, options: RenderOptions) -> None:
    """Refuse bad options before any work: unknown format or camera, non-positive fps or speed."""
    problems = []
    if out.suffix.lower() not in (".mp4", ".gif"):
        problems.append(Issue(None, None, "--out", f"'{out}' is neither .mp4 nor .gif", "name the file FILE.mp4 or "
                                                                                       "FILE.gif"))
    if options.camera not in CAMERAS:
        problems.append(Issue(None, None, "--camera", f"'{options.camera}' is not a camera",
                              "use follow, fixed or top"))
    if not 0.0 < options.fps <= 120.0:
        problems.append(Issue(None, None, "--fps", f"{options.fps} is not in (0, 120]", "e.g. --fps 25"))
    if not 0.0 < options.speed <= 100.0:
        problems.append(Issue(None, None, "--speed", f"{options.speed} is not in (0, 100]",
                              "e.g. --speed 2 for twice real time"))
    if problems:
        raise SpecError(problems)


# -- the MuJoCo scene ------------------------------------------------------------------------------------------


def _rgba(rgb: tuple[float, float, float]) -> str:
    return " ".join(f"{c:.3f}" for c in rgb) + " 1"


def scene_xml(shape: scene.Shapes, terrain: scene.TerrainShapes, width: int, height: int) -> str:
    """MJCF of the scene: ground, terrain boxes and height field, and one mocap body per body box, link and foot."""
    parts = [
        '<mujoco model="shc-render"><compiler angle="radian"/>',
        f'<visual><global offwidth="{width}" offheight="{height}"/><quality shadowsize="1024" offsamples="0"/>'
        '<headlight ambient="0.5 0.5 0.5" diffuse="0.6 0.6 0.6" specular="0.05 0.05 0.05"/>'
        '<map znear="0.01" zfar="50" haze="0.3"/><rgba haze="0.93 0.95 0.98 1"/></visual>',
        '<asset><texture name="ground" type="2d" builtin="checker" rgb1="1 1 1" rgb2="0.86 0.88 0.92" '
        'width="256" height="256"/><texture name="sky" type="skybox" builtin="gradient" rgb1="0.93 0.95 0.98" '
        'rgb2="0.75 0.82 0.92" width="32" height="256"/>'
        '<material name="ground" texture="ground" texrepeat="20 20" reflectance="0"/>',
        _mesh_asset(terrain.mesh),
        "</asset>",
        "<worldbody>",
        '<light pos="2 -2 4" dir="-0.4 0.4 -1" directional="true" castshadow="false" diffuse="0.6 0.6 0.6"/>',
        '<geom type="plane" size="20 20 0.1" material="ground"/>',
    ]
    if terrain.mesh is not None:
        # half a millimetre up: where the field is 0 it would flicker against the ground plane
        parts.append(f'<geom type="mesh" mesh="field" pos="0 0 0.0005" rgba="{_rgba(scene.TERRAIN_RGB)}"/>')
    for box in terrain.boxes:
        half = " ".join(f"{s / 2.0:.6f}" for s in box.size)
        centre = " ".join(f"{c:.6f}" for c in box.centre)
        parts.append(f'<geom type="box" pos="{centre}" size="{half}" euler="0 {box.pitch:.6f} 0" '
                     f'rgba="{_rgba(box.rgb)}"/>')
    size = " ".join(f"{s / 2.0:.6f}" for s in shape.body_size)
    com = " ".join(f"{c:.6f}" for c in shape.body_com)
    parts.append(f'<body name="body" mocap="true"><geom type="box" pos="{com}" size="{size}" '
                 f'rgba="{_rgba(scene.BODY_RGB)}"/></body>')
    origins = shape.chains.frames(shape.chains.default_joints())[..., :3, 3]
    for i, leg in enumerate(shape.legs):
        for k in range(shape.chains.joints):
            if not shape.link_real[i, k]:
                continue
            length = float(np.linalg.norm(origins[i, k + 1] - origins[i, k]))
            radius = float(shape.link_radius[i, k])
            if length < 0.004:  # a degenerate link (coincident origins): a small ball, as the URDF's cube
                geom = f'<geom name="{leg}_{k}" type="sphere" size="0.01" rgba="{_rgba(scene.LINK_RGB)}"/>'
            else:
                geom = (f'<geom name="{leg}_{k}" type="capsule" fromto="0 0 0 0 0 {length:.6f}" size="{radius:.6f}" '
                        f'rgba="{_rgba(scene.LINK_RGB)}"/>')
            parts.append(f'<body name="{leg}_{k}" mocap="true">{geom}</body>')
        parts.append(f'<body name="{leg}_foot" mocap="true"><geom name="{leg}_foot" type="sphere" '
                     f'size="{shape.foot_radius[i]:.6f}" rgba="{_rgba(scene.FOOT_RGB)}"/></body>')
    parts += ["</worldbody>", "</mujoco>"]
    return "\n".join(parts)


def _mesh_asset(mesh: tuple[np.ndarray, np.ndarray] | None) -> str:
    if mesh is None:
        return ""
    vertices, faces = mesh
    return (f'<mesh name="field" vertex="{" ".join(f"{v:.5f}" for v in vertices.ravel())}" '
            f'face="{" ".join(str(int(f)) for f in faces.ravel())}"/>')


class Renderer:
    """Frames of one robot's scene: :meth:`draw` places the model and returns an ``(H, W, 3)`` uint8 image."""

    def __init__(self, shape: scene.Shapes, terrain: scene.TerrainShapes, width: int, height: int) -> None:
        from shc_cli.backends.mujoco_.gl import enable_rendering

        try:
            mujoco = enable_rendering(fallback="egl")
        except ImportError as error:
            raise SpecError([Issue(None, None, "render", f"MuJoCo is not installed ({error})",
                                   install_hint())]) from None
        self.mujoco = mujoco
        self.shape = shape
        self.model = mujoco.MjModel.from_xml_string(scene_xml(shape, terrain, width, height))
        self.data = mujoco.MjData(self.model)
        try:
            self.renderer = mujoco.Renderer(self.model, height, width)
        except Exception as error:  # no OSMesa/EGL: one line saying what to install
            raise SpecError([Issue(None, None, "render", f"no offscreen OpenGL ({type(error).__name__}: {error})",
                                   "apt-get install libosmesa6 (or set MUJOCO_GL=egl with an EGL driver)")]) from None
        self.camera = mujoco.MjvCamera()
        self.camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        m = self.model
        self.body_mocap = int(m.body_mocapid[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "body")])
        self.link_slots: list[tuple[int, int, int]] = []
        self.foot_geoms: list[int] = []
        self.foot_mocap: list[int] = []
        for i, leg in enumerate(shape.legs):
            for k in range(shape.chains.joints):
                if shape.link_real[i, k]:
                    body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f"{leg}_{k}")
                    self.link_slots.append((i, k, int(m.body_mocapid[body])))
            body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f"{leg}_foot")
            self.foot_mocap.append(int(m.body_mocapid[body]))
            self.foot_geoms.append(mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"{leg}_foot"))
        self._rows = np.array([s[0] for s in self.link_slots])
        self._cols = np.array([s[1] for s in self.link_slots])
        self._mocap = np.array([s[2] for s in self.link_slots])

    def place(self, pose: scene.Poses, index: int, contact: np.ndarray | None) -> None:
        """Put every body where frame ``index`` of ``pose`` has it; feet coloured by ``contact`` ``(L,)``."""
        d, m = self.data, self.model
        d.mocap_pos[self.body_mocap] = pose.body_position[index]
        d.mocap_quat[self.body_mocap] = pose.body_quaternion[index]
        origins = pose.origins[index]
        start = origins[self._rows, self._cols]
        end = origins[self._rows, self._cols + 1]
        d.mocap_pos[self._mocap] = start
        d.mocap_quat[self._mocap] = scene.z_to(end - start)
        feet = origins[:, -1]
        for leg, (mocap, geom) in enumerate(zip(self.foot_mocap, self.foot_geoms, strict=True)):
            d.mocap_pos[mocap] = feet[leg]
            down = contact is not None and bool(contact[leg])
            m.geom_rgba[geom, :3] = scene.CONTACT_RGB if down else scene.FOOT_RGB
        self.mujoco.mj_kinematics(m, d)

    def look(self, target: np.ndarray, distance: float, azimuth: float, elevation: float) -> None:
        """Aim the camera at ``target`` [m] from ``distance`` [m], ``azimuth`` and ``elevation`` [deg]."""
        self.camera.lookat[:] = target
        self.camera.distance = distance
        self.camera.azimuth = azimuth
        self.camera.elevation = elevation

    def draw(self) -> np.ndarray:
        self.renderer.update_scene(self.data, self.camera)
        return np.asarray(self.renderer.render())

    def close(self) -> None:
        self.renderer.close()


# -- the run as frames -----------------------------------------------------------------------------------------


def frame_rows(t: np.ndarray, fps: float, speed: float) -> np.ndarray:
    """Log row shown in each video frame: frame ``j`` shows run time ``t₀ + j·speed/fps`` (the last row at or
    before it). ``floor((t_end − t₀)·fps/speed) + 1`` frames."""
    span = float(t[-1] - t[0])
    count = math.floor(span * fps / speed + 1e-9) + 1
    times = t[0] + np.arange(count) * speed / fps
    return np.asarray(np.clip(np.searchsorted(t, times + 1e-9, side="right") - 1, 0, len(t) - 1))


def measured_speed(run: RunLog) -> np.ndarray:
    """Horizontal body speed [m/s] per row: displacement over :data:`SPEED_WINDOW_S` centred on the row."""
    half = max(1, round(SPEED_WINDOW_S / run.dt / 2))
    xy = run.position[:, :2]
    ahead = xy[np.minimum(np.arange(len(xy)) + half, len(xy) - 1)]
    behind = xy[np.maximum(np.arange(len(xy)) - half, 0)]
    steps = np.minimum(np.arange(len(xy)) + half, len(xy) - 1) - np.maximum(np.arange(len(xy)) - half, 0)
    return np.asarray(np.linalg.norm(ahead - behind, axis=1) / np.maximum(steps, 1) / run.dt)


def _camera_path(run: RunLog, rows: np.ndarray, camera: str, body_length: float) -> Iterator[tuple[np.ndarray,
                                                                                                    float, float,
                                                                                                    float]]:
    """Camera target, distance, azimuth and elevation per frame."""
    size = max(body_length * 3.2, 0.8)
    if camera == "fixed":
        path = run.position[rows]
        low, high = path.min(axis=0), path.max(axis=0)
        centre = (low + high) / 2.0
        centre[2] = max(0.0, float(centre[2]) / 2.0)
        distance = max(size, float(np.linalg.norm(high[:2] - low[:2])) * 1.2 + size * 0.5)
        for _ in rows:
            yield centre, distance, 120.0, -25.0
        return
    # follow and top: the body, smoothed over a second so the camera does not shake with the gait
    window = max(1, round(1.0 / run.dt))
    kernel = np.ones(window) / window
    padded = np.pad(run.position, ((window // 2, window - 1 - window // 2), (0, 0)), mode="edge")
    smooth = np.stack([np.convolve(padded[:, i], kernel, mode="valid") for i in range(3)], axis=1)
    for row in rows:
        target = smooth[row].copy()
        if camera == "top":
            target[2] = 0.0
            yield target, size * 1.3, 90.0, -89.9
        else:
            target[2] = max(0.0, float(target[2]) * 0.5)
            yield target, size, 120.0, -25.0


def _font(size: int) -> Any:
    from PIL import ImageFont

    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow without FreeType sizes
        return ImageFont.load_default()


def overlay_lines(run: RunLog, row: int, speed: np.ndarray) -> list[str]:
    """The text over a frame: time, commanded and measured speed, robot and walk state."""
    commanded = float(np.hypot(run.desired[row, 0], run.desired[row, 1]))
    state = run.states[row, 0] if run.states is not None else ("RUNNING" if run.running[row] else "")
    return [f"t = {run.t[row]:6.2f} s",
            f"commanded {commanded:5.3f} m/s   measured {speed[row]:5.3f} m/s",
            f"{state} / {run.walk_state[row]}"]


def _annotate(image: np.ndarray, lines: list[str], font: Any, scale: float) -> np.ndarray:
    from PIL import Image, ImageDraw

    picture = Image.fromarray(image)
    draw = ImageDraw.Draw(picture, "RGBA")
    pad = max(2, round(6 * scale))
    step = max(8, round(20 * scale))
    width = max(draw.textlength(line, font=font) for line in lines)
    draw.rectangle((0, 0, width + 2 * pad, pad * 2 + step * len(lines)), fill=(255, 255, 255, 190))
    for i, line in enumerate(lines):
        draw.text((pad, pad + i * step), line, fill=(20, 20, 20), font=font)
    return np.asarray(picture)


def render_frames(run: RunLog, options: RenderOptions) -> Iterator[np.ndarray]:
    """The run's video frames, ``(H, W, 3)`` uint8 each, in order."""
    shape = scene.shapes(run.robot)
    terrain = scene.terrain_shapes(run.summary, run.robot)
    rows = frame_rows(run.t, options.fps, options.speed)
    pose = scene.poses(shape, run.joints[rows], run.position[rows], run.rpy[rows])
    speed = measured_speed(run)
    scale = options.height / 540.0
    font = _font(max(8, round(16 * scale)))
    renderer = Renderer(shape, terrain, options.width, options.height)
    try:
        cameras = _camera_path(run, rows, options.camera, max(shape.body_size[:2]))
        for index, (row, view) in enumerate(zip(rows, cameras, strict=True)):
            renderer.place(pose, index, run.contact[row])
            renderer.look(*view)
            yield _annotate(renderer.draw(), overlay_lines(run, int(row), speed), font, scale)
    finally:
        renderer.close()


def render_run(run: RunLog, out: Path, options: RenderOptions, progress: bool = False) -> RenderResult:
    """Render ``run`` into ``out`` (``.mp4`` or ``.gif``); the file appears only when complete."""
    check_options(out, options)
    for module in ("PIL", "imageio_ffmpeg"):
        try:
            __import__(module)
        except ImportError as error:
            raise SpecError([Issue(None, None, "render", f"{module} is not installed ({error})",
                                   install_hint())]) from None
    out.parent.mkdir(parents=True, exist_ok=True)
    partial = out.with_name(f".{out.name}.partial{out.suffix}")
    frames = render_frames(run, options)
    draw = encode = 0.0
    count = 0
    total = len(frame_rows(run.t, options.fps, options.speed))
    try:
        if out.suffix.lower() == ".gif":
            images = []
            for image, seconds in _timed(frames):
                started = time.perf_counter()
                images.append(_gif_frame(image))
                encode += time.perf_counter() - started
                draw += seconds
                count += 1
                _tick(progress, count, total)
            started = time.perf_counter()
            images[0].save(partial, save_all=True, append_images=images[1:], duration=round(1000.0 / options.fps),
                           loop=0, optimize=False, disposal=1)
            encode += time.perf_counter() - started
        else:
            import imageio_ffmpeg

            writer = imageio_ffmpeg.write_frames(
                str(partial), (options.width, options.height), fps=options.fps, codec="libx264", quality=6,
                pix_fmt_out="yuv420p", macro_block_size=2, ffmpeg_log_level="error",
                output_params=["-preset", "veryfast"])
            writer.send(None)
            try:
                for image, seconds in _timed(frames):
                    started = time.perf_counter()
                    writer.send(np.ascontiguousarray(image))
                    encode += time.perf_counter() - started
                    draw += seconds
                    count += 1
                    _tick(progress, count, total)
            finally:
                started = time.perf_counter()
                writer.close()
                encode += time.perf_counter() - started
        os.replace(partial, out)
    finally:
        if partial.exists():
            partial.unlink()
        if progress:
            print(file=sys.stderr)
    return RenderResult(out, count, draw, encode)


def _timed(frames: Iterator[np.ndarray]) -> Iterator[tuple[np.ndarray, float]]:
    while True:
        started = time.perf_counter()
        try:
            image = next(frames)
        except StopIteration:
            return
        yield image, time.perf_counter() - started


def _tick(progress: bool, count: int, total: int) -> None:
    if progress and (count % 25 == 0 or count == total):
        print(f"\rrendering {count}/{total} frames", end="", file=sys.stderr, flush=True)


def _gif_frame(image: np.ndarray) -> Any:
    from PIL import Image

    return Image.fromarray(image).quantize(colors=64, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
