"""Body sway for the four-legged ``quad_wave`` gait: an auto-pose set sized for one robot's stance.

The bundled ``quad_wave`` gait (8 base units, legs AR, BR, BL, AL) swings one leg at a time with no phase on
four feet: master phase (leg BL's) AR 1–3, BL 3–5, AL 5–7, BR 7–1. Without a body shift the centre of mass
sits on the diagonal of the three standing feet (zero static margin). The set moves the body sideways
towards the standing feet: +y (left) while the right legs swing (7–3), −y while the left legs swing (3–7).
It must cross the diagonal where one foot lands as the diagonally opposite one lifts (3 and 7), so the two
posers are 6 units long, centred on 1 and 5: they overlap one unit either side of 3 and 7 and the sway
crosses zero there with a slope; at mid-swing it is ``(2/3)³·2 = 0.59`` of the amplitude.

The amplitude is a third of the feet's lateral half-spread (the three standing feet's centroid lies that
far to the side of the body centre), in metres, so each robot needs its own set: ``poses/quad_wave.toml``
is sized for ``robots/quadruped.toml`` and ``shc import urdf`` writes one for the robot it imports
(docs/pose-files.md).
"""

from __future__ import annotations

from collections.abc import Iterable

SWAY_SHARE = 1.0 / 3.0
"""Sway amplitude as a share of the feet's lateral half-spread [ratio]: the standing triangle's centroid."""

WINDOWS = ((6, 4), (2, 0))
"""The two posers' [start, end) windows in the gait's base units: right legs' swings (+y), left legs' (−y)."""


def sway_amplitude(stance_y: Iterable[float]) -> float:
    """The sway amplitude [m] for feet standing at lateral positions ``stance_y`` [m]: a third of their mean
    distance from the body's x axis, rounded to the millimetre."""
    values = [abs(y) for y in stance_y]
    return round(SWAY_SHARE * sum(values) / len(values), 3)


def quad_wave_sway_toml(name: str, amplitude: float, robot: str) -> str:
    """The TOML text of a ``quad_wave`` sway set of ``amplitude`` [m] for the robot named ``robot``."""
    (left_start, left_end), (right_start, right_end) = WINDOWS
    return (
        f"# Body sway for the quad_wave gait, sized for {robot} (shc_cli/spec/sway.py, docs/pose-files.md):\n"
        "# the body moves sideways towards the three standing feet while a leg swings (AR 1-3, BL 3-5, AL 5-7,\n"
        "# BR 7-1 of the 8-unit cycle). Amplitude: a third of the feet's lateral half-spread.\n"
        f'name = "{name}"\n'
        f'description = "Sideways body sway for the quad_wave gait (sized for {robot})"\n'
        "pose_frequency = -1.0  # Hz; -1 = synchronised with the step cycle\n"
        "pose_phase_length = 8  # base units (stance_phase + swing_phase)\n"
        "\n"
        "[[poser]]  # while BR and AR swing (7-3): towards the left feet\n"
        f"start = {left_start}\nend = {left_end}\ny = {amplitude:g}  # m\n"
        "\n"
        "[[poser]]  # while BL and AL swing (3-7): towards the right feet\n"
        f"start = {right_start}\nend = {right_end}\ny = {-amplitude:g}  # m\n"
    )


__all__ = ["SWAY_SHARE", "WINDOWS", "quad_wave_sway_toml", "sway_amplitude"]
