"""``shc ros``: OpenSHC's node on ROS 1 — the one controller on the one run loop, with ROS as its input and output.

The node subscribes OpenSHC's remote topics (:mod:`shc_cli.ros.remote`), publishes what OpenSHC publishes
(:mod:`shc_cli.ros.outputs`) at the controller's rate against the wall clock (:mod:`shc_cli.loop.pacing`), and
drives a backend: ``none`` (outputs only, as OpenSHC with a separate hardware node), or a physics engine (the
robot simulated — a Gazebo-free OpenSHC simulation — with its measured joints and IMU published on
``/joint_states`` and ``/imu/data``). The robot comes from an shc robot file or from the parameter server's
``/syropod`` tree that OpenSHC's launch files load. Every session is also an ordinary run directory (log, summary).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from shc_cli.domain.live import open_live
from shc_cli.domain.result import RunResult

if TYPE_CHECKING:
    from shc_cli.loop.summary import RunSummary
    from shc_cli.ros.node import RosNode
    from shc_cli.ros.transport import Node
    from shc_cli.spec.gait import Gait
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)

NodeBackend = Literal["none", "mujoco", "pybullet", "bus"]
BACKENDS = ("none", "mujoco", "pybullet", "bus")
SERVER = "server"
"""The robot name that reads the robot from the parameter server (``/syropod/parameters`` …)."""


@dataclass(frozen=True)
class NodeConfig:
    """Options of ``shc ros``.

    Attributes:
        robot: robot file or bundled name, or ``"server"``: OpenSHC's parameters from the parameter server.
        backend: ``none`` (outputs only) or a physics engine.
        name: the node's name.
        master_uri: the ROS master (None: ``$ROS_MASTER_URI``).
        duration: stop after this many seconds of wall time (None: until Ctrl-C / SIGTERM / rosnode kill).
        out: the run directory (None: ``runs/<timestamp>-ros``).
        individual: publish the per-joint command topics (default: as the robot's parameters say, else on).
        combined: publish ``/desired_joint_states``.
        overwrite: replace an existing run directory.
        namespace: the parameter tree read for ``robot = "server"``.
        live: also stream the session on a Foxglove WebSocket server on 127.0.0.1:``live_port``.
        path: a path file to walk once the robot runs (more paths and goals arrive on ``<name>/path`` and
            ``/move_base_simple/goal``: :mod:`shc_cli.ros.path_remote`).
        ports, baud, dry_run, stop_state, on_fault, on_stop, profile_velocity: backend ``bus``: the servo buses and
            their safety, as ``run-hw``'s options (:class:`~shc_cli.domain.hardware.HardwareConfig`).
    """

    robot: str = "bullet"
    backend: NodeBackend = "none"
    name: str = "/shc"
    master_uri: str | None = None
    duration: float | None = None
    out: Path | None = None
    individual: bool = True
    combined: bool = True
    overwrite: bool = False
    namespace: str = "/syropod"
    live: bool = False
    live_port: int = 8765
    path: Path | None = None
    ports: tuple[str, ...] = ()
    baud: int | None = None
    dry_run: bool = False
    stop_state: str = "packed"
    on_fault: str = "torque-off"
    on_stop: str = "torque-off"
    profile_velocity: bool = False

    def __post_init__(self) -> None:
        from shc_cli.errors import Issue, SpecError, check_choice
        from shc_cli.loop.input_sources import STATES

        check_choice("--backend", self.backend, BACKENDS, "a backend")
        for option, value in (("--on-fault", self.on_fault), ("--on-stop", self.on_stop)):
            check_choice(option, value, ("hold", "torque-off"), "hold or torque-off")
        check_choice("--stop-state", self.stop_state, tuple(STATES), "a robot state")
        if (self.backend == "bus") != bool(self.ports):
            problem = ("the bus backend needs its serial ports" if self.ports == () else
                       f"--port is for the bus backend, not '{self.backend}'")
            raise SpecError([Issue(None, None, "--port", problem, "give --backend bus with --port DEV (once per "
                                   "bus, bus 0 first)")])


def run_node(config: NodeConfig, on_ready: Callable[[str], None] | None = None,
             open_node: Callable[[NodeConfig], Node] | None = None) -> RunResult:
    """Run the node until its duration passes, a signal, or ``rosnode kill``; returns the finished run directory.
    ``on_ready`` is told one line when the node is registered and waits for the remote. ``open_node`` makes the
    node (default: ROS 1's, :class:`~shc_cli.ros.node.RosNode`; ``shc ros2`` gives ROS 2's): the session, the
    remote, the outputs and the loop are the same on either.

    Raises:
        ShcError: bad input, or no ROS master (one line), before anything is written.
    """
    from shc_cli.loop.runlog import default_run_directory
    from shc_cli.ros.messages import MessageTypes
    from shc_cli.ros.node import RosNode

    directory = config.out or default_run_directory("ros")
    if config.path is not None:  # a bad path file is a one-line error before the node registers
        from shc_cli.spec.path import load_path

        load_path(config.path)
    node: Node = RosNode(config.name, MessageTypes(), config.master_uri) if open_node is None else open_node(config)
    try:
        robot, gait, pose_sets, gaits = _robot(node, config, directory)
        return _run(node, config, robot, gait, pose_sets, gaits, directory, on_ready)
    finally:
        node.close()


def _robot(node: Node, config: NodeConfig, directory: Path) -> tuple[Robot, Gait, Any, dict[str, Gait]]:
    """The robot, its gait and auto-pose sets, and the gaits ``gait_selection`` can choose."""
    import tempfile

    from shc_cli.loop.run_inputs import load_inputs
    from shc_cli.ros.node import RosNode
    from shc_cli.spec.loading import load_gait

    source = config.robot
    if source == SERVER:
        assert isinstance(node, RosNode)  # ROS 1's parameter server (shc ros2 refuses 'server' before its node)
        source = str(_robot_from_server(node, config.namespace, Path(tempfile.mkdtemp(prefix="shc-ros-"))))
    inputs = load_inputs(source, None, "0,0,0", None, None, default_s=1.0)
    gaits: dict[str, Gait] = {}
    for name in ("wave", "amble", "ripple", "tripod"):
        try:
            candidate = load_gait(name).gait
        except Exception:
            continue
        if candidate is not None and set(candidate.offset_multiplier) >= set(inputs.robot.legs):
            gaits[name] = candidate
    return inputs.robot, inputs.gait, inputs.pose_sets, gaits


def _robot_from_server(node: RosNode, namespace: str, folder: Path) -> Path:
    """Write the robot (and its gaits) of the parameter server's OpenSHC tree as shc files; the robot file."""
    from shc_cli.errors import Issue, SpecError
    from shc_cli.interop.openshc import gaits_from_openshc, robot_from_openshc
    from shc_cli.outputs import write_text
    from shc_cli.spec.toml_out import dump_toml

    if not node.has_param(f"{namespace}/parameters"):
        raise SpecError([Issue(None, None, "robot", f"the parameter server has no {namespace}/parameters",
                               "load OpenSHC's parameters first (rosparam load ROBOT.yaml, or its launch file), "
                               "or give an shc robot file")])
    params = node.get_param(f"{namespace}/parameters")
    assert isinstance(params, dict)
    name = str(params.get("syropod_type", "server_robot"))
    try:
        tree, _unused = robot_from_openshc(params, name)
    except (KeyError, TypeError, ValueError) as error:
        raise SpecError([Issue(None, None, f"{namespace}/parameters", f"missing or malformed OpenSHC parameter: "
                               f"{error}", "compare with OpenSHC's config/default.yaml")]) from None
    if node.has_param(f"{namespace}/gait_parameters"):
        gait_params = node.get_param(f"{namespace}/gait_parameters")
        assert isinstance(gait_params, dict)
        for gait_name, gait in gaits_from_openshc(gait_params).items():
            write_text(folder / "gaits" / f"{gait_name}.toml", dump_toml(gait))
        if tree["walker"]["gait"] in gaits_from_openshc(gait_params):
            tree["walker"]["gait"] = f"../gaits/{tree['walker']['gait']}.toml"
    path = folder / "robots" / f"{name}.toml"
    write_text(path, f"# From the parameter server's {namespace} tree (shc ros).\n{dump_toml(tree)}")
    log.info("robot %s read from the parameter server (%s)", name, namespace)
    return path


def _run(node: Node, config: NodeConfig, robot: Robot, gait: Gait, pose_sets: Any, gaits: dict[str, Gait],
         directory: Path, on_ready: Callable[[str], None] | None) -> RunResult:
    if config.backend == "none":
        return _run_outputs_only(node, config, robot, gait, pose_sets, gaits, directory, on_ready)
    if config.backend == "bus":
        from shc_cli.domain.ros_bus import run_on_bus

        return run_on_bus(node, config, robot, gait, pose_sets, gaits, directory, on_ready)
    return _run_simulated(node, config, robot, gait, pose_sets, gaits, directory, on_ready)


def _run_outputs_only(node: Node, config: NodeConfig, robot: Robot, gait: Gait, pose_sets: Any,
                      gaits: dict[str, Gait], directory: Path, on_ready: Callable[[str], None] | None) -> RunResult:
    """Backend none: the controller's targets are taken as reached (OpenSHC with a hardware node of the user's)."""
    from shc_cli.backends.kinematic import KinematicBackend
    from shc_cli.control.controller import Controller
    from shc_cli.domain.ros_session import NodeSession
    from shc_cli.loop.plan_summary import PlanRecord, plan_summary
    from shc_cli.loop.run_loop import Observer, RunLoop
    from shc_cli.loop.runlog import RunWriter
    from shc_cli.loop.session import execute

    # OpenSHC starts from the measured joints when /joint_states gives them all (shc ros2; shc ros: the defaults)
    controller = Controller(robot, gait, joints=node.measured_joints(robot), pose_sets=pose_sets)
    writer = RunWriter(directory, robot, config.overwrite)
    writer.write_robot(robot)
    record = PlanRecord(controller)
    session = NodeSession(node, config, robot, controller, gaits, sensors=False)
    observers: list[Observer[None]] = [record, session.outputs, session.clock, session.deadline]
    stream = open_live(config.live_port, robot, controller, sensors=False) if config.live else None
    if stream is not None:
        observers.insert(2, stream[1])
    path_fields = session.keep_path(writer.partial)
    loop = RunLoop(controller, KinematicBackend(), session.source, writer, None, observers=observers,
                   flush_every=100)
    session.requested = lambda: loop.requested
    session.ready(node, config, robot, gait, on_ready)
    started = time.perf_counter()

    def summarise(_: object) -> RunSummary:
        summary = plan_summary(robot, controller, record, time.perf_counter() - started, writer.partial)
        return summary.updated(backend=config.backend, ros_master=node.master_uri, node=node.name,
                               **session.clock.statistics(), **path_fields())

    try:
        path, summary, _ = execute(loop, writer, summarise, None)
    finally:
        if stream is not None:
            stream[0].close()
    return RunResult(path, summary)


def _run_simulated(node: Node, config: NodeConfig, robot: Robot, gait: Gait, pose_sets: Any,
                   gaits: dict[str, Gait], directory: Path, on_ready: Callable[[str], None] | None) -> RunResult:
    """A physics engine: the robot simulated in real time, its measured joints, IMU, foot forces and power published
    (``/joint_states``, ``/imu/data``, ``/<LEG>/foot_force``, ``/shc/power``) — OpenSHC's Gazebo set-up without
    Gazebo. The engine's options are ``shc simulate``'s defaults for the robot (flat ground, 400 Hz)."""
    from shc_cli.backends.engine import Reading
    from shc_cli.backends.simulated import SimulatedBackend, open_world
    from shc_cli.control.controller import Controller
    from shc_cli.domain.config import SimulationConfig
    from shc_cli.domain.ros_session import NodeSession
    from shc_cli.loop.physics_summary import PhysicsRecord
    from shc_cli.loop.run_loop import Observer, RunLoop
    from shc_cli.loop.runlog import LogRecorder, RunDirectory
    from shc_cli.loop.session import execute

    sim = SimulationConfig(robot=config.robot, engine=config.backend)
    with RunDirectory(directory, config.overwrite) as run:
        world = open_world(robot, sim.engine_options(robot))
        with SimulatedBackend(robot, world) as backend:
            controller = Controller(robot, gait, joints=backend.start(), pose_sets=pose_sets)
            run.write_robot(robot)
            record = PhysicsRecord(robot, backend, sim.airborne)
            session = NodeSession(node, config, robot, controller, gaits, sensors=True)
            observers: list[Observer[Reading]] = [record, session.outputs, session.clock, session.deadline]
            stream = open_live(config.live_port, robot, controller, sensors=True) if config.live else None
            if stream is not None:
                observers.insert(2, stream[1])
            path_fields = session.keep_path(run.partial)
            loop = RunLoop(controller, backend, session.source, LogRecorder(run, robot, backend), None,
                           observers=observers, flush_every=100)
            session.requested = lambda: loop.requested
            session.ready(node, config, robot, gait, on_ready)

            def summarise(_: object) -> RunSummary:
                return record.summary(run.partial, sim.scenario, controller.gait.name, controller).updated(
                    engine=world.name, engine_version=world.version, engine_warnings=world.warnings,
                    backend=config.backend, ros_master=node.master_uri, node=node.name,
                    **session.clock.statistics(), **path_fields())

            try:
                path, summary, _ = execute(loop, run, summarise, None)
            finally:
                if stream is not None:
                    stream[0].close()
    return RunResult(path, summary)
