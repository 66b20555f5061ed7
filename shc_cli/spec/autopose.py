"""Auto-pose files: OpenSHC's cyclic body posing sets (study §7.3, §11.5) as TOML.

One file is one set (OpenSHC ``<name>_pose`` in ``auto_pose.yaml``)::

    name = "tripod"
    pose_frequency = -1.0      # Hz; -1 = synchronised with the step cycle
    pose_phase_length = 4      # base units of one posing cycle

    [[poser]]                  # one auto-poser: a window of the cycle and its amplitudes
    start = 1
    end = 3
    z = 0.01
    roll = -0.05

    [negation.AR]              # the window in which leg AR does not see the body auto pose
    start = 1
    end = 3
    transition_ratio = 0.0

Phases are in *base units* (the gait's ``stance_phase + swing_phase`` when synchronised); the controller
scales them by the step cycle's normaliser. A window may wrap past the cycle end (``start > end``).
A leg without a ``[negation.LEG]`` table is never negated (OpenSHC's ``LegPoser`` initial values).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from pydantic import Field, field_validator

from shc_cli.errors import Issue, SpecError
from shc_cli.spec.gait import Gait
from shc_cli.spec.loading import Located, _validate, resolve
from shc_cli.spec.robot import Metres, Radians, Strict
from shc_cli.spec.source import Document, origins, unwrap

SYNCHRONISED = -1.0
"""``pose_frequency`` value that locks the posing cycle to the step cycle."""


class Poser(Strict):
    """One auto-poser (OpenSHC ``AutoPoser``): a window of the posing cycle and a pose amplitude.

    Over its window the pose rises from zero to the amplitude (first half, ``A(4t³ − 3t⁴)``) and falls
    back (second half, ``A(1 − t)³(1 + 3t)``). All posers' poses are composed into the body auto pose.
    """

    start: int = Field(ge=0, description="first phase of the window [base units]; 0 ≤ start < pose_phase_length")
    end: int = Field(ge=0, description="phase that ends the window (excluded) [base units]; start > end wraps")
    x: Metres = Field(0.0, description="forward translation amplitude [m]")
    y: Metres = Field(0.0, description="left translation amplitude [m]")
    z: Metres = Field(0.0, description="upward translation amplitude [m]")
    roll: Radians = Field(0.0, description="roll amplitude, about x [rad]")
    pitch: Radians = Field(0.0, description="pitch amplitude, about y [rad]")
    yaw: Radians = Field(0.0, description="yaw amplitude, about z [rad]")
    gravity: Metres = Field(
        0.0, description="translation amplitude along the gravity direction [m]; when non-zero it replaces x/y/z")


class Negation(Strict):
    """A leg's auto-pose negation window (OpenSHC ``pose_negation_phase_starts/ends``, ``negation_transition_ratio``).

    While negated the leg is posed without the body auto pose (typically during its own swing).
    """

    start: int = Field(ge=0, description="phase at which negation switches on [base units]; 0 = the cycle length")
    end: int = Field(ge=0, description="last negated phase [base units] (included); 0 = the cycle length")
    transition_ratio: float = Field(
        0.0, ge=0.0, allow_inf_nan=False,
        description="share of the window used to blend in and out of negation [ratio]; 0 = switch at once")


class AutoPoseSet(Strict):
    """One auto-pose set (OpenSHC ``<gait>_pose`` in ``auto_pose.yaml``)."""

    name: str = Field(description="short name, e.g. 'tripod' (the gait it is written for)")
    description: str = Field("", description="one sentence for people")
    pose_frequency: float = Field(
        description="posing cycle frequency [Hz]; -1 = synchronised with the step cycle [OpenSHC: pose_frequency]")
    pose_phase_length: int = Field(
        gt=0, description="base units in one posing cycle [units]; equals the gait's stance + swing when "
                          "synchronised [OpenSHC: pose_phase_length]")
    poser: list[Poser] = Field(default_factory=list, description="the auto-posers, composed in order")
    negation: dict[str, Negation] = Field(
        default_factory=dict, description="leg id → window in which that leg ignores the body auto pose")

    @field_validator("pose_frequency")
    @classmethod
    def _frequency(cls, value: float) -> float:
        if value != SYNCHRONISED and not value > 0.0:
            raise ValueError(f"must be -1 or a positive frequency, got {value:g}; write -1 to follow the step cycle")
        return value

    @property
    def synchronised(self) -> bool:
        """True when the posing cycle is the step cycle (``pose_frequency = -1``)."""
        return self.pose_frequency == SYNCHRONISED


@dataclass
class LoadedPoseSet(Located):
    """An auto-pose file, loaded: the pose set and where each of its fields was written."""

    pose_set: AutoPoseSet = field(kw_only=True)


def _window_issues(loaded: Located, pose_set: AutoPoseSet) -> list[Issue]:
    """Windows inside the cycle; a poser window that OpenSHC could never close is refused."""
    issues = []
    length = pose_set.pose_phase_length
    for index, poser in enumerate(pose_set.poser):
        for key in ("start", "end"):
            value = getattr(poser, key)
            if value >= length:
                fix = "write 0 for the cycle end (phase N never occurs, so the poser would never stop)" \
                    if value == length else f"use 0 to {length - 1}"
                issues.append(loaded.issue(("poser", index, key), f"{value} lies outside the cycle of {length} units",
                                           fix))
        if poser.start == poser.end:
            issues.append(loaded.issue(("poser", index, "end"), f"equals start ({poser.start}): the window is empty",
                                       "give the window at least one unit"))
    for leg, negation in pose_set.negation.items():
        outside = False
        for key in ("start", "end"):
            value = getattr(negation, key)
            if value > length:
                outside = True
                issues.append(loaded.issue(("negation", leg, key), f"{value} lies outside the cycle of {length} units",
                                           f"use 0 to {length}"))
        if not outside and negation.start % length == negation.end % length:
            issues.append(loaded.issue(("negation", leg, "end"), f"equals start ({negation.start}) on the cycle: "
                                       "the window is empty", f"remove [negation.{leg}] if the leg is never negated"))
    return issues


def load_pose_set(name_or_path: str | Path, relative_to: Path | None = None) -> LoadedPoseSet:
    """Read and validate an auto-pose file (by bundled name, e.g. ``tripod``, or path)."""
    path = resolve("poses", name_or_path, relative_to)
    document = Document(path)
    data = document.sourced()
    located = Located(path=path, origin_map=origins(data), documents={path: document})
    pose_set = _validate(AutoPoseSet, unwrap(data), located)
    issues = _window_issues(located, pose_set)
    if issues:
        raise SpecError(issues)
    return LoadedPoseSet(path=path, origin_map=located.origin_map, documents=located.documents, pose_set=pose_set)


def pose_set_name(auto_pose_type: str, gait: Gait) -> str:
    """The set a robot's ``pose.auto_pose_type`` names: ``auto`` → the set named after the gait (OpenSHC)."""
    return gait.name if auto_pose_type == "auto" else auto_pose_type


def load_auto_pose_set(auto_pose_type: str, gait: Gait, relative_to: Path | None = None) -> LoadedPoseSet:
    """Load the set for ``auto_pose_type`` and ``gait`` (``auto`` + ``tripod`` → ``poses/tripod.toml``)."""
    return load_pose_set(pose_set_name(auto_pose_type, gait), relative_to)


def compatibility_issues(loaded: LoadedPoseSet, gait: Gait, leg_ids: Sequence[str]) -> list[Issue]:
    """What stops this set from driving ``gait`` on a robot with legs ``leg_ids``.

    A synchronised set's phases are base units of the gait's cycle, so its length must be the gait's
    ``stance_phase + swing_phase``. Negation tables must name legs of the robot (OpenSHC looks every leg up in
    the maps and throws on a missing one; here a missing leg is simply never negated).
    """
    pose_set = loaded.pose_set
    issues = []
    if pose_set.synchronised and pose_set.pose_phase_length != gait.base_length:
        issues.append(loaded.issue(
            ("pose_phase_length",),
            f"set '{pose_set.name}' is written for a {pose_set.pose_phase_length}-unit cycle, but gait "
            f"'{gait.name}' has {gait.base_length} (stance_phase + swing_phase)",
            "use the pose set written for this gait, rewrite the windows in the gait's units, or turn auto "
            "posing off (pose.auto = false)"))
    for leg in pose_set.negation:
        if leg not in leg_ids:
            issues.append(loaded.issue(("negation", leg), f"no leg '{leg}' on this robot",
                                       f"legs: {', '.join(leg_ids)}"))
    return issues


__all__ = ["AutoPoseSet", "LoadedPoseSet", "Negation", "Poser", "compatibility_issues", "load_auto_pose_set",
           "load_pose_set", "pose_set_name"]
