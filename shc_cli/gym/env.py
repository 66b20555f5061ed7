"""``shc/Walk-v0``: the one controller on ``shc simulate``'s physics backend, one control cycle per step.

Each episode opens the physics world (:func:`~shc_cli.backends.simulated.open_world`), builds the controller from
its joints and runs the one run loop (:class:`~shc_cli.loop.run_loop.RunLoop`) cycle by cycle: :meth:`WalkEnv.reset`
runs the start-up to RUNNING, every :meth:`WalkEnv.step` one cycle of the run's command timeline (the
``command`` velocity for ``duration`` seconds, as ``shc simulate --velocity --duration``) with the action applied:
to the command (``gait``) or to the controller's joint targets (``residual``, ``joints``;
:mod:`shc_cli.loop.policy.actions`). The episode is terminated when the robot falls and truncated when the
timeline is over. Nothing is written unless ``out=DIR`` (:mod:`.episodes`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, SupportsFloat

import gymnasium
import numpy as np
from gymnasium import spaces

from shc_cli.backends.base import InputSource
from shc_cli.backends.engine import Reading
from shc_cli.backends.simulated import SimulatedBackend, open_world
from shc_cli.control.controller import Command, Controller
from shc_cli.control.states import RobotState
from shc_cli.control.verified_limits import source_for
from shc_cli.domain.config import SimulationConfig
from shc_cli.gym.episodes import EpisodeRecord
from shc_cli.loop.policy.actions import ACTIONS, ActionName, GaitAction, JointAction, ResidualAction
from shc_cli.loop.policy.observe import Rewards, fallen, observation_bounds, observation_names, observe
from shc_cli.loop.run_inputs import RunInputs, load_inputs
from shc_cli.loop.run_loop import Adjust, NullRecorder, RunLoop, StartUp
from shc_cli.model.chains import JointSlots
from shc_cli.spec.robot import Robot

Info = dict[str, Any]
"""gymnasium's info and options dicts (its Env API types them so)."""
RESET_OPTIONS = ("friction", "mass_scale", "terrain", "servo")
"""The options :meth:`WalkEnv.reset` takes (domain randomisation), each for that episode only."""


class _Commands:
    """The run's command timeline, changed by the gait action (an input source of the loop)."""

    def __init__(self, timeline: InputSource, env: WalkEnv) -> None:
        self.timeline, self.env = timeline, env

    def next(self) -> Command | None:
        command = self.timeline.next()
        if command is None or self.env.gait is None:
            return command
        return self.env.gait_command(command)

    def close(self) -> None:
        self.timeline.close()


class WalkEnv(gymnasium.Env[np.ndarray, np.ndarray]):
    """The controller as a Gymnasium environment (docs/gym.md).

    Args:
        robot: robot file or bundled name.
        action: ``"gait"``, ``"residual"`` or ``"joints"`` (:mod:`shc_cli.loop.policy.actions`).
        engine: ``"mujoco"`` or ``"pybullet"``.
        terrain: as ``shc simulate --terrain``.
        command: the velocity input (x, y, yaw) in the robot's input mode, or ``"VX,VY,WZ"``.
        reward: weights of the reward terms by name (:data:`~shc_cli.loop.policy.observe.TERMS`; missing: default).
        duration: seconds of walking per episode (truncation) [s].
        gait: gait file or name (None: the robot's).
        friction: lateral friction of feet and terrain (as ``shc simulate --friction``).
        residual_limit: bound of the residual tip offsets [m].
        out: write each episode as a run directory ``out/episode-NNNN`` (:mod:`.episodes`); None: nothing.
    """

    metadata: Info = {"render_modes": []}  # noqa: RUF012 (gymnasium's class attribute)

    def __init__(self, robot: str = "bullet", action: ActionName = "gait", engine: str = "mujoco",
                 terrain: str = "flat", command: tuple[float, float, float] | str = (1.0, 0.0, 0.0),
                 reward: dict[str, float] | None = None, duration: float = 10.0, gait: str | None = None,
                 friction: float = 0.9, residual_limit: float = 0.02, out: str | Path | None = None) -> None:
        if action not in ACTIONS:
            raise ValueError(f"action: '{action}' is not one of {', '.join(ACTIONS)}")
        velocity = command if isinstance(command, str) else ",".join(repr(float(v)) for v in command)
        self.config = SimulationConfig(robot=robot, gait=gait, velocity=velocity, duration=duration,
                                       terrain=terrain, engine=engine, friction=friction)
        o = self.config
        self.inputs: RunInputs = load_inputs(o.robot, o.gait, o.velocity, o.duration, None, default_s=duration,
                                             walking=o.walking, robot_change=o.apply_switches)
        self.robot: Robot = self.inputs.robot
        self.action_name = action
        self.gait = GaitAction(self.robot) if action == "gait" else None
        self.residual = ResidualAction(self.robot, residual_limit) if action == "residual" else None
        self.joints = JointAction(self.robot) if action == "joints" else None
        actor = self.gait or self.residual or self.joints
        assert actor is not None
        self.action_space = actor.space
        self.action_size = int(actor.space.shape[0])
        self._adjust: Adjust | None = (self.residual.adjust if self.residual is not None
                                       else self.joints.adjust if self.joints is not None else None)
        self._slots = JointSlots.of(self.robot)
        self._steps = 0
        self.names = observation_names(self.robot)
        self.observation_space = spaces.Box(*observation_bounds(self.names))
        self.rewards = Rewards(self.robot, reward or {})
        self._loop: RunLoop[Reading] | None = None
        self._backend: SimulatedBackend | None = None
        self._cycles_in_step = 0
        self._period = 1
        self.seed_used = 0
        self.out = None if out is None else Path(out)
        self.episodes = 0
        self._record: EpisodeRecord | None = None
        self.written: list[Path] = []
        """The run directories written so far (``out``)."""

    def gait_command(self, command: Command) -> Command:
        """The timeline's command with the gait action (its parameters sent once a step cycle)."""
        assert self.gait is not None and self._loop is not None
        controller = self._loop.controller
        self._cycles_in_step += 1
        new_cycle = self._cycles_in_step >= self._period
        if new_cycle:
            self._cycles_in_step, self._period = 0, controller.cycle.period
        return self.gait.command(command, controller.parameters, new_cycle)

    def reset(self, *, seed: int | None = None,
              options: Info | None = None) -> tuple[np.ndarray, Info]:
        """A new episode: the world rebuilt (seeded: terrain blocks, IMU noise), started up to RUNNING.

        Options (this episode only): ``friction``, ``mass_scale`` (of every mass), ``terrain``, ``servo`` (factors of
        the robot's ``[servo]`` numbers by name, e.g. ``{"winding_resistance": 1.1}``: within ``shc fit``'s
        uncertainty)."""
        super().reset(seed=seed)
        if seed is not None:
            self.seed_used = seed
        options = dict(options or {})
        unknown = sorted(set(options) - set(RESET_OPTIONS))
        if unknown:
            raise ValueError(f"reset: no option '{unknown[0]}' (options: {', '.join(RESET_OPTIONS)})")
        self.close()
        robot = self.robot if "mass_scale" not in options else scaled_masses(self.robot, float(options["mass_scale"]))
        if "servo" in options:
            robot = scaled_servo(robot, dict(options["servo"]))
        config = self.config.model_copy(update={"seed": self.seed_used, **{
            key: options[key] for key in ("friction", "terrain") if key in options}})
        if "terrain" in options:
            config = SimulationConfig(**config.model_dump())  # parse and check the terrain
        world = open_world(robot, config.engine_options(robot))
        self._backend = backend = SimulatedBackend(robot, world)
        controller = Controller(robot, self.inputs.gait, joints=backend.start(), pose_sets=self.inputs.pose_sets,
                                speed_shares=source_for(robot))
        source = _Commands(self.inputs.source(controller), self)
        if self.out is not None:
            self.episodes += 1
            self._record = record = EpisodeRecord(self.out / f"episode-{self.episodes:04d}", robot, backend, config)
            self._loop = loop = RunLoop(controller, backend, source, record.recorder, StartUp.of(robot),
                                        observers=[record.observer])
        else:
            self._loop = loop = RunLoop(controller, backend, source, NullRecorder(), StartUp.of(robot))
        self._cycles_in_step, self._period = 0, 1
        if self.gait is not None:
            self.gait.set(np.zeros(self.action_size))
        if self.joints is not None:
            self.joints.targets = None
        if self.residual is not None:
            self.residual.set(np.zeros(self.action_size))
        loop.begin()
        cycle = None
        while controller.state != RobotState.RUNNING:
            cycle = loop.step()
            if cycle is None:
                raise RuntimeError(f"{robot.name}: the episode ended during the start-up ({loop.stop_reason})")
        assert cycle is not None
        self._steps = 0
        return observe(self._slots, cycle.reading, cycle.out), {"start_up_cycles": loop.cycle}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, SupportsFloat, bool, bool, Info]:
        loop = self._loop
        if loop is None:
            raise RuntimeError("step() before reset()")
        actor = self.gait or self.residual or self.joints
        assert actor is not None
        actor.set(np.asarray(action))
        cycle = loop.step(self._adjust)
        if cycle is None:  # the timeline is over
            obs = np.zeros(len(self.names), dtype=np.float32)
            return obs, 0.0, False, True, {"stop_reason": loop.stop_reason}
        self._steps += 1
        fell = fallen(self.robot, cycle.reading)
        terms = self.rewards.terms(cycle.out, cycle.reading, fell)
        obs = observe(self._slots, cycle.reading, cycle.out)
        truncated = not fell and self._steps >= self.inputs.cycles
        return obs, self.rewards.total(terms), fell, truncated, {"terms": terms, "joints": cycle.applied,
                                                                **self.rewards.measures(cycle.reading)}

    def close(self) -> None:
        if self._record is not None and self._loop is not None:
            self.written.append(self._record.finish(self._loop.finish(), self._loop.controller))
            self._record = None
        if self._backend is not None:
            self._backend.close()
            self._backend = self._loop = None


def scaled_masses(robot: Robot, scale: float) -> Robot:
    """``robot`` with its body and every link mass given in its file times ``scale``."""
    if not scale > 0:
        raise ValueError(f"reset: mass_scale {scale:g} must be positive")
    legs = {name: leg.model_copy(update={"joints": {
        joint_name: joint.model_copy(update={"mass": None if joint.mass is None else joint.mass * scale})
        for joint_name, joint in leg.joints.items()}}) for name, leg in robot.legs.items()}
    return robot.model_copy(update={"body": robot.body.model_copy(update={"mass": robot.body.mass * scale}),
                                    "legs": legs})


def scaled_servo(robot: Robot, factors: dict[str, float]) -> Robot:
    """``robot`` with the named numbers of its ``[servo]`` table times their factors."""
    servo = robot.servo
    update: dict[str, float] = {}
    for name, factor in factors.items():
        value = getattr(servo, name, None)
        if not isinstance(value, float) or isinstance(value, bool):
            numbers = sorted(k for k, v in servo.model_dump().items() if isinstance(v, float))
            raise ValueError(f"reset: servo has no number '{name}' (numbers: {', '.join(numbers)})")
        if not float(factor) > 0:
            raise ValueError(f"reset: servo factor {name}={factor:g} must be positive")
        update[name] = value * float(factor)
    return robot.model_copy(update={"servo": servo.model_copy(update=update)})
