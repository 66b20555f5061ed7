"""Terrains of the simulators: parsed from ``--terrain`` text, described as geometry, queried analytically.

``parse_terrain`` turns ``flat``, ``ramp:DEG``, ``blocks[:LOW,HIGH[,SIZE]]``, ``stairs:RISE,RUN`` or
``heightfield:FILE[,SCALE[,CELL]]`` into a :class:`TerrainSpec` (bad text raises one
:class:`~shc_cli.errors.SpecError` line); :class:`Terrain` holds what every physics engine builds from it — the
boxes of ramps, stairs and block fields (:meth:`Terrain.boxes`), the height-field samples (:attr:`Terrain.field`)
— and :meth:`Terrain.height_at` gives the ground height under any point from the same geometry (no ray
casting). The robot starts at the origin facing +x; every terrain keeps the start area (x < 0.4 m) flat at
z = 0. Geometry, defaults and units: ``docs/terrains.md``. Nothing here imports a physics engine: PyBullet builds
the bodies in :mod:`shc_cli.backends.pybullet_.terrain_bodies`, MuJoCo in :mod:`shc_cli.backends.mujoco_.mjcf`.

Every terrain has an infinite ground plane at z = 0; features stand on it. Boxes give exact surfaces.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from shc_cli.errors import Issue, SpecError

TerrainKind = Literal["flat", "ramp", "blocks", "stairs", "heightfield"]

START_END_X = 0.4
"""The start area x < START_END_X [m] is flat at z = 0 on every terrain (the robot starts at the origin)."""
FEATURE_START_X = 0.5
"""Where ramps, stairs and height fields begin [m]."""
BLOCKS_START_X = 0.4
"""Where the block field begins [m]."""
FEATURE_END_X = 6.0
"""Where the ramp stops rising, the last stair begins at the latest and the block field ends [m]."""
LANDING_END_X = 10.0
"""Where the flat top landing of ramps and stairs ends (a drop to z = 0 beyond) [m]."""
HALF_WIDTH = 1.5
"""Ramps, stairs and the block field span |y| <= HALF_WIDTH [m]."""

DEFAULT_BLOCK_LOW = 0.04
"""Default lowest block height [m] (ATHENA's rough-terrain trials)."""
DEFAULT_BLOCK_HIGH = 0.13
"""Default highest block height [m] (ATHENA's rough-terrain trials)."""
DEFAULT_BLOCK_SIZE = 0.1
"""Default side of a square block [m]."""
MIN_BLOCK_SIZE = 0.05
"""Smallest block side [m]: smaller ones multiply the boxes (and the physics cost) for no foot-scale effect."""
MAX_FEATURE_HEIGHT = 1.0
"""Largest block height and stair rise [m]; larger numbers are most likely centimetres."""
MAX_RAMP_DEG = 45.0
"""Steepest ramp [deg]."""
DEFAULT_CSV_SCALE = 1.0
"""Default height scale of a CSV height field (its numbers are metres)."""
DEFAULT_PNG_SCALE = 0.1
"""Default height of full white in a PNG height field [m]."""
DEFAULT_CELL = 0.05
"""Default distance between height-field samples [m]."""
MAX_HEIGHTFIELD_SAMPLES = 250_000
"""Largest height field (e.g. 500 × 500): PyBullet needs ~2.5 s for this many samples, 19 s for 1200 × 1200."""

_SYNTAX = "flat, ramp:DEG, blocks[:LOW,HIGH[,SIZE]], stairs:RISE,RUN or heightfield:FILE[,SCALE[,CELL]]"
_KINDS: tuple[TerrainKind, ...] = ("flat", "ramp", "blocks", "stairs", "heightfield")
GROUND_RGBA = (0.82, 0.82, 0.80, 1.0)
"""Colour of the ground plane (red, green, blue, alpha)."""
FEATURE_RGBA = (0.62, 0.55, 0.47, 1.0)
"""Colour of ramps, stairs, blocks and height fields."""


@dataclass(frozen=True)
class TerrainSpec:
    """A parsed ``--terrain`` value; only the fields of its ``kind`` matter.

    Attributes:
        kind: ``flat``, ``ramp``, ``blocks``, ``stairs`` or ``heightfield``.
        text: The text it was parsed from (for messages and run logs).
        degrees: Ramp slope [deg].
        low: Lowest block height [m].
        high: Highest block height [m].
        size: Side of a square block [m].
        rise: Stair rise [m].
        run: Stair run (tread depth) [m].
        path: Height-field file.
        scale: Height-field scale (CSV: multiplier of its metres; PNG: metres of full white).
        cell: Distance between height-field samples [m].
        heights: Height-field samples [m] after scaling, ``heights[i][j]`` at x index i (along +x) and
            y index j (along +y), i.e. the file's columns and its rows from the bottom line up.
    """

    kind: TerrainKind
    text: str = "flat"
    degrees: float = 0.0
    low: float = DEFAULT_BLOCK_LOW
    high: float = DEFAULT_BLOCK_HIGH
    size: float = DEFAULT_BLOCK_SIZE
    rise: float = 0.0
    run: float = 0.0
    path: Path | None = None
    scale: float = DEFAULT_CSV_SCALE
    cell: float = DEFAULT_CELL
    heights: tuple[tuple[float, ...], ...] = ()

    def __str__(self) -> str:
        return self.text


# -- parsing ---------------------------------------------------------------------------------------------------


def _error(problem: str, fix: str) -> SpecError:
    return SpecError([Issue(None, None, "--terrain", " ".join(problem.split()), " ".join(fix.split()))])


def _number(text: str, what: str, example: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise _error(f"{what} '{text}' is not a number", f"write a number, e.g. {example}") from None
    if not math.isfinite(value):
        raise _error(f"{what} '{text}' is not finite", f"write a finite number, e.g. {example}")
    return value


def _parameters(kind: str, rest: str | None, allowed: tuple[int, ...], usage: str) -> list[str]:
    values = [] if rest is None else [part.strip() for part in rest.split(",")]
    if len(values) not in allowed:
        counts = {0: "no values", 1: "1 value"}
        want = " or ".join(counts.get(n, f"{n} values") for n in allowed)
        got = "none" if not values else f"{counts.get(len(values), f'{len(values)} values')} ({rest})"
        raise _error(f"{kind} takes {want}, got {got}", f"write {usage}")
    if any(not value for value in values):
        raise _error(f"{kind} has an empty value in '{rest}'", f"write {usage}")
    return values


def parse_terrain(text: str) -> TerrainSpec:
    """Parse a ``--terrain`` value; raises a one-line :class:`~shc_cli.errors.SpecError` on bad text.

    Height-field files are read here (so a missing or malformed file is reported before the simulator starts).
    """
    stripped = text.strip()
    name, colon, rest_text = stripped.partition(":")
    name = name.strip().lower()
    rest = rest_text.strip() if colon else None
    if not name:
        raise _error("no terrain given", f"choose {_SYNTAX}")
    if name not in _KINDS:
        close = difflib.get_close_matches(name, _KINDS, n=1, cutoff=0.5)
        hint = f"did you mean '{close[0]}'? " if close else ""
        raise _error(f"unknown terrain '{name}'", f"{hint}choose {_SYNTAX}")
    if name == "flat":
        _parameters("flat", rest, (0,), "flat")
        return TerrainSpec("flat", stripped)
    if name == "ramp":
        (degrees_text,) = _parameters("ramp", rest, (1,), "ramp:DEG, e.g. ramp:10")
        degrees = _number(degrees_text, "ramp slope", "ramp:10")
        if not 0.0 < degrees <= MAX_RAMP_DEG:
            raise _error(f"ramp slope {degrees:g}° is outside (0, {MAX_RAMP_DEG:g}]°",
                         "give a positive angle in degrees; the ramp rises along +x, e.g. ramp:10")
        return TerrainSpec("ramp", stripped, degrees=degrees)
    if name == "blocks":
        return _parse_blocks(stripped, rest)
    if name == "stairs":
        rise_text, run_text = _parameters("stairs", rest, (2,), "stairs:RISE,RUN in metres, e.g. stairs:0.05,0.3")
        rise = _number(rise_text, "stair rise", "stairs:0.05,0.3")
        run = _number(run_text, "stair run", "stairs:0.05,0.3")
        if not 0.0 < rise <= MAX_FEATURE_HEIGHT:
            raise _error(f"stair rise {rise:g} m is outside (0, {MAX_FEATURE_HEIGHT:g}] m",
                         "give the rise in metres, e.g. stairs:0.05,0.3")
        if not 0.05 <= run <= FEATURE_END_X - FEATURE_START_X:
            raise _error(f"stair run {run:g} m is outside [0.05, {FEATURE_END_X - FEATURE_START_X:g}] m",
                         "give the tread depth in metres, e.g. stairs:0.05,0.3")
        return TerrainSpec("stairs", stripped, rise=rise, run=run)
    return _parse_heightfield(stripped, rest)


def _parse_blocks(text: str, rest: str | None) -> TerrainSpec:
    usage = "blocks, blocks:LOW,HIGH or blocks:LOW,HIGH,SIZE in metres, e.g. blocks:0.04,0.13,0.1"
    values = _parameters("blocks", rest, (0, 2, 3), usage)
    low, high, size = DEFAULT_BLOCK_LOW, DEFAULT_BLOCK_HIGH, DEFAULT_BLOCK_SIZE
    if values:
        low = _number(values[0], "block LOW", "blocks:0.04,0.13")
        high = _number(values[1], "block HIGH", "blocks:0.04,0.13")
    if len(values) == 3:
        size = _number(values[2], "block SIZE", "blocks:0.04,0.13,0.1")
    if low < 0.0:
        raise _error(f"block LOW {low:g} m is negative", "give heights from 0 up, e.g. blocks:0.04,0.13")
    if low > high:
        raise _error(f"block LOW {low:g} m is above HIGH {high:g} m", f"swap them: blocks:{high:g},{low:g}")
    if not 0.0 < high <= MAX_FEATURE_HEIGHT:
        raise _error(f"block HIGH {high:g} m is outside (0, {MAX_FEATURE_HEIGHT:g}] m",
                     "give heights in metres, e.g. blocks:0.04,0.13")
    if not MIN_BLOCK_SIZE <= size <= 1.0:
        raise _error(f"block SIZE {size:g} m is outside [{MIN_BLOCK_SIZE:g}, 1] m",
                     "give the block side in metres, e.g. blocks:0.04,0.13,0.1")
    return TerrainSpec("blocks", text, low=low, high=high, size=size)


def _parse_heightfield(text: str, rest: str | None) -> TerrainSpec:
    usage = "heightfield:FILE[,SCALE[,CELL]] with a .csv or .png file, e.g. heightfield:field.csv,1,0.05"
    values = _parameters("heightfield", rest, (1, 2, 3), usage)
    path = Path(values[0]).expanduser()
    suffix = path.suffix.lower()
    if suffix not in (".csv", ".png"):
        raise _error(f"height field '{path}' is neither .csv nor .png", usage.replace("with", "using"))
    if not path.is_file():
        raise _error(f"height field '{path}' not found",
                     "check the path; a relative one starts at the current directory")
    default_scale = DEFAULT_CSV_SCALE if suffix == ".csv" else DEFAULT_PNG_SCALE
    scale = _number(values[1], "height-field SCALE", "heightfield:field.png,0.1") if len(values) > 1 else default_scale
    cell = _number(values[2], "height-field CELL", "heightfield:field.csv,1,0.05") if len(values) > 2 else DEFAULT_CELL
    if scale <= 0.0:
        raise _error(f"height-field SCALE {scale:g} is not positive", "give a positive scale, e.g. 1 for metres")
    if not 0.005 <= cell <= 1.0:
        raise _error(f"height-field CELL {cell:g} m is outside [0.005, 1] m",
                     "give the sample spacing in metres, e.g. 0.05")
    grid = _read_grid(path) * scale
    if grid.shape[0] < 2 or grid.shape[1] < 2:
        raise _error(f"height field '{path}' has {grid.shape[0]} × {grid.shape[1]} samples",
                     "give at least 2 rows and 2 columns")
    if grid.size > MAX_HEIGHTFIELD_SAMPLES:
        raise _error(f"height field '{path}' has {grid.size} samples, more than {MAX_HEIGHTFIELD_SAMPLES}",
                     "downsample it and raise CELL to match")
    if not np.all(np.isfinite(grid)):
        raise _error(f"height field '{path}' holds nan or inf", "write finite heights")
    if float(grid.min()) < 0.0:
        raise _error(f"height field '{path}' goes down to {float(grid.min()):g} m, below the ground at 0",
                     "shift the heights so the lowest is 0 or more")
    heights = grid[::-1, :].T  # file rows run from +y (first line) to −y; columns along +x
    return TerrainSpec("heightfield", text, path=path, scale=scale, cell=cell,
                       heights=tuple(tuple(float(h) for h in column) for column in heights))


def _read_grid(path: Path) -> np.ndarray:
    """The samples of a CSV (metres) or PNG (0..1 of full white) file as rows × columns."""
    if path.suffix.lower() == ".csv":
        try:
            grid = np.loadtxt(path, delimiter=",", dtype=float, ndmin=2, comments="#")
        except (OSError, ValueError) as error:
            first = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
            raise _error(f"cannot read height field '{path}': {first}",
                         "write rows of comma-separated heights in metres, all rows equally long") from None
        return np.asarray(grid, dtype=float)
    try:
        from matplotlib import image

        pixels = np.asarray(image.imread(path), dtype=float)
    except Exception as error:  # PIL/matplotlib raise many types for a bad image
        first = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise _error(f"cannot read height field '{path}': {first}", "give an 8- or 16-bit greyscale PNG") from None
    if pixels.ndim == 3:  # colour: average R, G, B; ignore alpha
        pixels = pixels[:, :, :3].mean(axis=2) if pixels.shape[2] >= 3 else pixels[:, :, 0]
    return pixels


# -- geometry --------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Box:
    """An axis-aligned box, or one pitched about y by ``pitch`` [rad] (a ramp)."""

    center: tuple[float, float, float]
    size: tuple[float, float, float]
    pitch: float = 0.0


def _block_grid(spec: TerrainSpec) -> tuple[int, int]:
    """Blocks along x and along y."""
    nx = max(1, math.floor((FEATURE_END_X - BLOCKS_START_X) / spec.size + 1e-9))
    ny = max(1, math.floor(2.0 * HALF_WIDTH / spec.size + 1e-9))
    return nx, ny


def _stair_count(spec: TerrainSpec) -> int:
    return max(1, math.floor((FEATURE_END_X - FEATURE_START_X) / spec.run + 1e-9))


class Terrain:
    """A terrain's geometry (what an engine builds) and the analytic ground height.

    Attributes:
        spec: What was built.
        seed: The seed the block heights were drawn with.
        body_ids: The engine's ids of its bodies (PyBullet: body ids, the ground plane first); empty if not built.
        block_heights: Block heights ``(nx, ny)`` [m] for ``blocks`` (x index along +x from x = 0.4,
            y index along +y from the field's −y edge), otherwise ``None``.
        field: Height-field samples ``(nx, ny)`` [m] for ``heightfield`` (as :attr:`TerrainSpec.heights`),
            otherwise ``None``.
        diagonal: Whose triangulation of the height-field cells :meth:`height_at` follows (``pybullet`` or
            ``mujoco``: the engines split a cell along different diagonals).
    """

    def __init__(self, spec: TerrainSpec, seed: int, body_ids: tuple[int, ...] = (),
                 diagonal: Literal["pybullet", "mujoco"] = "pybullet") -> None:
        self.spec = spec
        self.diagonal = diagonal
        self.seed = seed
        self.body_ids = body_ids
        self.block_heights: np.ndarray | None = None
        self.field: np.ndarray | None = None
        if spec.kind == "blocks":
            nx, ny = _block_grid(spec)
            heights = np.random.default_rng(seed).uniform(spec.low, spec.high, size=(nx, ny))
            heights[heights < 1e-6] = 0.0  # too thin to build: no box, and height_at says 0
            heights.setflags(write=False)
            self.block_heights = heights
        elif spec.kind == "heightfield":
            field = np.array(spec.heights, dtype=float)
            field.setflags(write=False)
            self.field = field

    def height_above(self, position: Sequence[float] | np.ndarray) -> float:
        """Height of ``position`` (x, y, z) [m] above the ground under it, from the terrain's geometry [m]: the
        engines' height ray where it hits nothing."""
        x, y, z = (float(v) for v in position)
        return z - self.height_at(x, y)

    def height_at(self, x: float, y: float) -> float:
        """Ground height [m] under the point (x, y) [m], from the terrain's geometry.

        On a vertical face (a block or stair edge) the cell on the +x / +y side counts.
        """
        spec = self.spec
        if spec.kind == "flat" or x < START_END_X:
            return 0.0
        if spec.kind == "heightfield":
            return self._field_height(x, y)
        if abs(y) > HALF_WIDTH:
            return 0.0
        if spec.kind == "ramp":
            if not FEATURE_START_X <= x <= LANDING_END_X:
                return 0.0
            return math.tan(math.radians(spec.degrees)) * (min(x, FEATURE_END_X) - FEATURE_START_X)
        if spec.kind == "stairs":
            if not FEATURE_START_X <= x < LANDING_END_X:
                return 0.0
            step = min(_stair_count(spec), math.floor((x - FEATURE_START_X) / spec.run + 1e-12) + 1)
            return step * spec.rise
        assert self.block_heights is not None
        nx, ny = self.block_heights.shape
        i = math.floor((x - BLOCKS_START_X) / spec.size)
        j = math.floor((y + ny * spec.size / 2.0) / spec.size)
        if 0 <= i < nx and 0 <= j < ny:
            return float(self.block_heights[i, j])
        return 0.0

    def _field_height(self, x: float, y: float) -> float:
        """Height on the engine's triangulation: PyBullet splits each cell along its (i+1, j)–(i, j+1) diagonal,
        MuJoCo along its (i, j)–(i+1, j+1) one."""
        assert self.field is not None
        field, cell = self.field, self.spec.cell
        nx, ny = field.shape
        u = (x - FEATURE_START_X) / cell
        v = (y + (ny - 1) * cell / 2.0) / cell
        if not (0.0 <= u <= nx - 1 and 0.0 <= v <= ny - 1):
            return 0.0
        i, j = min(int(u), nx - 2), min(int(v), ny - 2)
        fx, fy = u - i, v - j
        h00, h10, h01, h11 = field[i, j], field[i + 1, j], field[i, j + 1], field[i + 1, j + 1]
        if self.diagonal == "mujoco":
            if fx >= fy:
                return float(h00 + fx * (h10 - h00) + fy * (h11 - h10))
            return float(h00 + fy * (h01 - h00) + fx * (h11 - h01))
        if fx + fy <= 1.0:
            return float(h00 + fx * (h10 - h00) + fy * (h01 - h00))
        return float(h11 + (1.0 - fx) * (h01 - h11) + (1.0 - fy) * (h10 - h11))

    def boxes(self) -> list[Box]:
        """The boxes of a ramp, stairs or block field (none for flat and height fields)."""
        spec = self.spec
        width = 2.0 * HALF_WIDTH
        if spec.kind == "ramp":
            theta = math.radians(spec.degrees)
            top = math.tan(theta) * (FEATURE_END_X - FEATURE_START_X)
            length = (FEATURE_END_X - FEATURE_START_X) / math.cos(theta)
            thickness = top * math.cos(theta) + 0.05  # deep enough to be solid down to z = 0 at the top
            normal = (-math.sin(theta), math.cos(theta))
            mid = (FEATURE_START_X + length / 2.0 * math.cos(theta), length / 2.0 * math.sin(theta))
            centre = (mid[0] - thickness / 2.0 * normal[0], 0.0, mid[1] - thickness / 2.0 * normal[1])
            plateau = LANDING_END_X - FEATURE_END_X
            return [Box(centre, (length, width, thickness), pitch=-theta),
                    Box((FEATURE_END_X + plateau / 2.0, 0.0, top / 2.0), (plateau, width, top))]
        if spec.kind == "stairs":
            steps = _stair_count(spec)
            boxes = []
            for k in range(1, steps + 1):
                x0 = FEATURE_START_X + (k - 1) * spec.run
                x1 = LANDING_END_X if k == steps else x0 + spec.run
                boxes.append(Box(((x0 + x1) / 2.0, 0.0, k * spec.rise / 2.0), (x1 - x0, width, k * spec.rise)))
            return boxes
        if spec.kind == "blocks":
            assert self.block_heights is not None
            nx, ny = self.block_heights.shape
            y0 = -ny * spec.size / 2.0
            return [Box((BLOCKS_START_X + (i + 0.5) * spec.size, y0 + (j + 0.5) * spec.size, float(h) / 2.0),
                         (spec.size, spec.size, float(h)))
                    for i in range(nx) for j in range(ny)
                    if (h := self.block_heights[i, j]) > 0.0]
        return []
