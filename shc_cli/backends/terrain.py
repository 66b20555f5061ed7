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

TerrainKind = Literal["flat", "ramp", "blocks", "stairs", "stairs-down", "heightfield", "stones", "gaps", "slope",
                      "steps", "obstacles"]
LEVEL_KINDS = ("slope", "steps", "obstacles", "stones", "gaps")
"""legged_gym's kinds, ``NAME:D`` with a difficulty D in [0, 1], scaled to the robot (:func:`robot_scale`)."""
RAISED_KINDS = ("stairs-down", "stones", "gaps")
"""Terrains whose start is a raised platform (x from :data:`PLATFORM_START_X` to :data:`FEATURE_START_X`)."""

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
PLATFORM_START_X = -2.0
"""The raised start platform of :data:`RAISED_KINDS` begins here (a drop to z = 0 behind it) [m]."""
REFERENCE_CLEARANCE = 0.5
"""Body height [m] of the robot legged_gym's terrain numbers are made for (ANYmal C stands ≈ 0.5 m high): a level
terrain's lengths and heights are legged_gym's × ``body_clearance / REFERENCE_CLEARANCE`` (:func:`robot_scale`)."""

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

_SYNTAX = ("flat, ramp:DEG, blocks[:LOW,HIGH[,SIZE]], stairs:RISE,RUN, stairs-down:RISE,RUN, "
           "heightfield:FILE[,SCALE[,CELL]] or slope|steps|obstacles|stones|gaps:D")
_KINDS: tuple[TerrainKind, ...] = ("flat", "ramp", "blocks", "stairs", "stairs-down", "heightfield", "slope", "steps",
                                   "obstacles", "stones", "gaps")
GROUND_RGBA = (0.82, 0.82, 0.80, 1.0)
"""Colour of the ground plane (red, green, blue, alpha)."""
FEATURE_RGBA = (0.62, 0.55, 0.47, 1.0)
"""Colour of ramps, stairs, blocks and height fields."""


@dataclass(frozen=True)
class TerrainSpec:
    """A parsed ``--terrain`` value; only the fields of its ``kind`` matter.

    Attributes:
        kind: ``flat``, ``ramp``, ``blocks``, ``stairs``, ``stairs-down``, ``heightfield``, ``stones``, ``gaps``
            or one of :data:`LEVEL_KINDS` (resolved to geometry for a robot by :func:`resolve`).
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
        level: Difficulty of a level kind, in [0, 1].
        choices: Block heights drawn from these [m] instead of uniformly from [low, high] (``obstacles``).
        gap: Gap between stones, or width of a gap [m].
        depth: Height of the stones' and gaps' platform above the ground [m].
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
    level: float = 0.0
    choices: tuple[float, ...] = ()
    gap: float = 0.0
    depth: float = 0.0

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
    if name in ("stairs", "stairs-down"):
        example = f"{name}:0.05,0.3"
        rise_text, run_text = _parameters(name, rest, (2,), f"{name}:RISE,RUN in metres, e.g. {example}")
        rise = _number(rise_text, "stair rise", example)
        run = _number(run_text, "stair run", example)
        if not 0.0 < rise <= MAX_FEATURE_HEIGHT:
            raise _error(f"stair rise {rise:g} m is outside (0, {MAX_FEATURE_HEIGHT:g}] m",
                         f"give the rise in metres, e.g. {example}")
        if not 0.05 <= run <= FEATURE_END_X - FEATURE_START_X:
            raise _error(f"stair run {run:g} m is outside [0.05, {FEATURE_END_X - FEATURE_START_X:g}] m",
                         f"give the tread depth in metres, e.g. {example}")
        return TerrainSpec(name, stripped, rise=rise, run=run)
    if name in LEVEL_KINDS:
        (level_text,) = _parameters(name, rest, (1,), f"{name}:D with a difficulty D from 0 to 1, e.g. {name}:0.5")
        level = _number(level_text, f"{name} difficulty", f"{name}:0.5")
        if not 0.0 <= level <= 1.0:
            raise _error(f"{name} difficulty {level:g} is outside [0, 1]",
                         f"give a difficulty from 0 (easiest) to 1 (hardest), e.g. {name}:0.5")
        return TerrainSpec(name, stripped, level=level)
    return _parse_heightfield(stripped, rest)


def robot_scale(body_clearance: float) -> float:
    """The factor a level terrain's lengths and heights are scaled by: the robot's ``walker.body_clearance``
    over :data:`REFERENCE_CLEARANCE` (legged_gym's numbers are for a robot about 0.5 m high)."""
    return body_clearance / REFERENCE_CLEARANCE


def resolve(spec: TerrainSpec, scale: float) -> TerrainSpec:
    """The geometry of a level terrain (legged_gym's ``terrain.py`` numbers × ``scale``, docs/terrains.md); any
    other spec unchanged. slope: a ramp of 0.4·D rad; steps: stairs of (0.05 + 0.18·D)·s rise and 0.31·s run;
    obstacles: blocks of side 1·s, each of height 0, h/2 or h with h = (0.05 + 0.2·D)·s; stones: square stones of
    side 1.5·(1.05 − D)·s, 0.1·s apart (0.05·s at D = 0), on pillars 1·s high; gaps: gaps D·s wide between
    platform pieces 1·s long, 1·s deep."""
    d, s, text = spec.level, scale, spec.text
    if spec.kind == "slope":
        return TerrainSpec("ramp", text, degrees=math.degrees(0.4 * d), level=d)
    if spec.kind == "steps":
        return TerrainSpec("stairs", text, rise=(0.05 + 0.18 * d) * s, run=max(0.05, 0.31 * s), level=d)
    if spec.kind == "obstacles":
        h = (0.05 + 0.2 * d) * s
        size = min(1.0, max(MIN_BLOCK_SIZE, 1.0 * s))
        return TerrainSpec("blocks", text, low=0.0, high=h, size=size, choices=(0.0, h / 2.0, h), level=d)
    if spec.kind == "stones" and not spec.depth:
        gap = (0.05 if d == 0.0 else 0.1) * s
        return TerrainSpec("stones", text, size=1.5 * (1.05 - d) * s, gap=gap, depth=1.0 * s, level=d)
    if spec.kind == "gaps" and not spec.depth:
        return TerrainSpec("gaps", text, size=1.0 * s, gap=d * s, depth=1.0 * s, level=d)
    return spec


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


def _odd_count(span: float) -> int:
    """Stones across: an odd number, so one row is centred on y = 0, the robot's path."""
    n = max(1, math.floor(span + 1e-9))
    return n if n % 2 else n - 1


def _stair_count(spec: TerrainSpec) -> int:
    return max(1, math.floor((FEATURE_END_X - FEATURE_START_X) / spec.run + 1e-9))


class Terrain:
    """A terrain's geometry (what an engine builds) and the analytic ground height.

    Attributes:
        spec: What was built (a level kind resolved for the robot's ``scale``, :func:`resolve`).
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
                 diagonal: Literal["pybullet", "mujoco"] = "pybullet", scale: float = 1.0) -> None:
        spec = resolve(spec, scale)
        self.spec = spec
        self.diagonal = diagonal
        self.seed = seed
        self.body_ids = body_ids
        self.block_heights: np.ndarray | None = None
        self.field: np.ndarray | None = None
        if spec.kind == "blocks":
            nx, ny = _block_grid(spec)
            rng = np.random.default_rng(seed)
            heights = (rng.choice(np.array(spec.choices), size=(nx, ny)) if spec.choices
                       else rng.uniform(spec.low, spec.high, size=(nx, ny)))
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
        if spec.kind in RAISED_KINDS:
            return self._raised_height(x, y)
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

    @property
    def start_height(self) -> float:
        """Height of the start area (x < :data:`START_END_X`) [m]: 0, or the top of a raised start platform."""
        return self.height_at(0.0, 0.0)

    def _raised_height(self, x: float, y: float) -> float:
        """Ground height of ``stairs-down``, ``stones`` and ``gaps``: a platform from :data:`PLATFORM_START_X`."""
        spec = self.spec
        if abs(y) > HALF_WIDTH or not PLATFORM_START_X <= x < LANDING_END_X:
            return 0.0
        if spec.kind == "stairs-down":
            steps = _stair_count(spec)
            if x < FEATURE_START_X:
                return steps * spec.rise
            return max(0, steps - math.floor((x - FEATURE_START_X) / spec.run + 1e-12) - 1) * spec.rise
        if x < FEATURE_START_X:
            return spec.depth
        if spec.kind == "stones":  # (the rectangles' arithmetic, without walking thousands of them)
            pitch = spec.size + spec.gap
            nx = max(1, math.floor((FEATURE_END_X - FEATURE_START_X) / pitch + 1e-9))
            ny = _odd_count(2.0 * HALF_WIDTH / pitch)
            if x >= FEATURE_START_X + nx * pitch + spec.gap:
                return spec.depth
            u, v = x - FEATURE_START_X - spec.gap, y + ny * pitch / 2.0 - spec.gap / 2.0
            i, j = math.floor(u / pitch), math.floor(v / pitch)
            inside = 0 <= i < nx and 0 <= j < ny and u - i * pitch < spec.size and v - j * pitch < spec.size
            return spec.depth if inside else 0.0
        for x0, x1, y0, y1 in self._platform_rectangles():
            if x0 <= x < x1 and y0 <= y < y1:
                return spec.depth
        return 0.0

    def _platform_rectangles(self) -> list[tuple[float, float, float, float]]:
        """Tops (x0, x1, y0, y1) of the ``stones``' and ``gaps``' platform pieces, all ``spec.depth`` high."""
        spec = self.spec
        start = (PLATFORM_START_X, FEATURE_START_X, -HALF_WIDTH, HALF_WIDTH)
        if spec.kind == "gaps":
            if spec.gap <= 0.0:
                return [(PLATFORM_START_X, LANDING_END_X, -HALF_WIDTH, HALF_WIDTH)]
            pieces, x = [start], FEATURE_START_X + spec.gap
            while x + spec.size < FEATURE_END_X:
                pieces.append((x, x + spec.size, -HALF_WIDTH, HALF_WIDTH))
                x += spec.size + spec.gap
            return [*pieces, (x, LANDING_END_X, -HALF_WIDTH, HALF_WIDTH)]
        pitch = spec.size + spec.gap  # stones: a stone centred in every pitch × pitch cell
        nx = max(1, math.floor((FEATURE_END_X - FEATURE_START_X) / pitch + 1e-9))
        ny = _odd_count(2.0 * HALF_WIDTH / pitch)
        x0, y0 = FEATURE_START_X + spec.gap, -ny * pitch / 2.0 + spec.gap / 2.0
        stones = [(x0 + i * pitch, x0 + i * pitch + spec.size, y0 + j * pitch, y0 + j * pitch + spec.size)
                  for i in range(nx) for j in range(ny)]
        end = FEATURE_START_X + nx * pitch + spec.gap
        return [start, *stones, (end, LANDING_END_X, -HALF_WIDTH, HALF_WIDTH)]

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
        """The boxes of a ramp, stairs, a block field or a raised platform (none for flat, height fields and a
        0° slope)."""
        spec = self.spec
        width = 2.0 * HALF_WIDTH
        if spec.kind == "ramp" and spec.degrees > 0.0:
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
        if spec.kind == "stairs-down":
            steps = _stair_count(spec)
            boxes = [Box(((PLATFORM_START_X + FEATURE_START_X) / 2.0, 0.0, steps * spec.rise / 2.0),
                         (FEATURE_START_X - PLATFORM_START_X, width, steps * spec.rise))]
            for k in range(1, steps):
                x0 = FEATURE_START_X + (k - 1) * spec.run
                height = (steps - k) * spec.rise
                boxes.append(Box((x0 + spec.run / 2.0, 0.0, height / 2.0), (spec.run, width, height)))
            return boxes
        if spec.kind in ("stones", "gaps"):
            return [Box(((x0 + x1) / 2.0, (y0 + y1) / 2.0, spec.depth / 2.0), (x1 - x0, y1 - y0, spec.depth))
                    for x0, x1, y0, y1 in self._platform_rectangles()]
        if spec.kind == "blocks":
            assert self.block_heights is not None
            nx, ny = self.block_heights.shape
            y0 = -ny * spec.size / 2.0
            return [Box((BLOCKS_START_X + (i + 0.5) * spec.size, y0 + (j + 0.5) * spec.size, float(h) / 2.0),
                         (spec.size, spec.size, float(h)))
                    for i in range(nx) for j in range(ny)
                    if (h := self.block_heights[i, j]) > 0.0]
        return []
