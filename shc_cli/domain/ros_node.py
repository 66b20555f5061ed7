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
from pathlib import Path
from typing import TYPE_CHECKING, cast

from shc_cli.domain.live import live_observer
from shc_cli.domain.result import RunResult
from shc_cli.domain.ros_config import BACKENDS as BACKENDS
from shc_cli.domain.ros_config import SERVER
from shc_cli.domain.ros_config import NodeBackend as NodeBackend
from shc_cli.domain.ros_config import NodeConfig as NodeConfig

if TYPE_CHECKING:
    from shc_cli.backends.engine import Reading
    from shc_cli.loop.assembly import Assembly, Finished, RunSpec
    from shc_cli.record.summary import RunSummary
    from shc_cli.ros.node import RosNode
    from shc_cli.ros.transport import Node
    from shc_cli.spec.autopose import AutoPoseSet
    from shc_cli.spec.gait import Gait
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)


def run_node(config: NodeConfig, on_ready: Callable[[str], None] | None = None,
             open_node: Callable[[NodeConfig], Node] | None = None) -> RunResult:
    """Run the node until its duration passes, a signal, or ``rosnode kill``; returns the finished run directory.
    ``on_ready`` is told one line when the node is registered and waits for the remote. ``open_node`` makes the
    node (default: ROS 1's, :class:`~shc_cli.ros.node.RosNode`; ``shc ros2`` gives ROS 2's): the session, the
    remote, the outputs and the loop are the same on either.

    Raises:
        ShcError: bad input, or no ROS master (one line), before anything is written.
    """
    from shc_cli.record.runlog import default_run_directory
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


def _robot(node: Node, config: NodeConfig,
           directory: Path) -> tuple[Robot, Gait, dict[str, AutoPoseSet], dict[str, Gait]]:
    """The robot, its gait and auto-pose sets, and the gaits ``gait_selection`` can choose."""
    import tempfile

    from shc_cli.loop.run_inputs import load_inputs

    if config.robot == SERVER:  # the server's robot as shc files, read, then removed (the run keeps robot.toml)
        ros1 = cast("RosNode", node)  # ROS 1's parameter server (shc ros2 refuses 'server' before its node opens)
        with tempfile.TemporaryDirectory(prefix="shc-ros-") as folder:
            source = str(_robot_from_server(ros1, config.namespace, Path(folder)))
            inputs = load_inputs(source, None, "0,0,0", None, None, default_s=1.0)
    else:
        inputs = load_inputs(config.robot, None, "0,0,0", None, None, default_s=1.0)
    return inputs.robot, inputs.gait, inputs.pose_sets, selectable_gaits(inputs.robot)


SELECTABLE_GAITS = ("wave", "amble", "ripple", "tripod")
"""The bundled gaits ``gait_selection`` cycles through (OpenSHC's order), those that fit the robot's legs."""


def selectable_gaits(robot: Robot) -> dict[str, Gait]:
    """The bundled gaits of :data:`SELECTABLE_GAITS` whose offsets name every leg of ``robot``; a gait that does
    not load is left out with its reason logged (a bug other than bad input is raised, not swallowed)."""
    from shc_cli.errors import ShcError
    from shc_cli.spec.loading import load_gait

    gaits: dict[str, Gait] = {}
    for name in SELECTABLE_GAITS:
        try:
            candidate = load_gait(name).gait
        except ShcError as error:
            log.warning("gait %s is not offered to gait_selection: %s", name, str(error).splitlines()[0])
            continue
        if candidate is not None and set(candidate.offset_multiplier) >= set(robot.legs):
            gaits[name] = candidate
        else:
            log.debug("gait %s is not offered to gait_selection: it does not name every leg of %s", name, robot.name)
    return gaits


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


def _run(node: Node, config: NodeConfig, robot: Robot, gait: Gait, pose_sets: dict[str, AutoPoseSet],
         gaits: dict[str, Gait], directory: Path, on_ready: Callable[[str], None] | None) -> RunResult:
    if config.backend == "none":
        return _run_outputs_only(node, config, robot, gait, pose_sets, gaits, directory, on_ready)
    if config.backend == "bus":
        from shc_cli.domain.ros_bus import run_on_bus

        return run_on_bus(node, config, robot, gait, pose_sets, gaits, directory, on_ready)
    return _run_simulated(node, config, robot, gait, pose_sets, gaits, directory, on_ready)


def _run_outputs_only(node: Node, config: NodeConfig, robot: Robot, gait: Gait, pose_sets: dict[str, AutoPoseSet],
                      gaits: dict[str, Gait], directory: Path, on_ready: Callable[[str], None] | None) -> RunResult:
    """Backend none: the controller's targets are taken as reached (OpenSHC with a hardware node of the user's)."""
    from shc_cli.loop.assembly import assemble

    def build(parts: Assembly) -> RunSpec[None]:
        from shc_cli.control.controller import Controller
        from shc_cli.control.verified_limits import source_for
        from shc_cli.domain.ros_session import NodeSession
        from shc_cli.loop.assembly import RunSpec
        from shc_cli.loop.plan_summary import PlanRecord, plan_summary
        from shc_cli.record.runlog import RunWriter
        from shc_cli.ros.measured import MeasuredBackend, MeasuredInputs

        # OpenSHC's start-up: /joint_states, /imu/data and /tip_states subscribed, the measured joints waited for
        measured = MeasuredInputs(node, robot)
        controller = Controller(robot, gait, joints=measured.wait_for_joints(config.joint_states_timeout),
                                pose_sets=pose_sets, speed_shares=source_for(robot))
        writer = RunWriter(directory, robot, config.overwrite)
        parts.enter(writer)
        writer.write_robot(robot)
        record = PlanRecord(controller)
        session = NodeSession(node, config, robot, controller, gaits, sensors=False)
        stream = live_observer(parts, config.live, config.live_port, robot, controller, sensors=False)
        path_fields = session.keep_path(writer.partial)
        session.ready(node, config, robot, gait, on_ready)
        started = time.perf_counter()

        def summarise(finished: Finished) -> RunSummary:
            return plan_summary(robot, controller, record, time.perf_counter() - started, finished.directory, {
                "backend": config.backend, "ros_master": node.master_uri, "node": node.name, **finished.shared},
                                ("plan", "ros"))

        return RunSpec(controller, MeasuredBackend(measured), session.source, writer, None, writer, summarise,
                       observers=[record, measured.feed_efforts(session.outputs), session.outputs], live=stream,
                       pacing=session.clock,
                       late_observers=[session.deadline], path_fields=path_fields, on_loop=session.watch,
                       flush_every=100)

    return RunResult(*assemble(build).pair)


def _run_simulated(node: Node, config: NodeConfig, robot: Robot, gait: Gait, pose_sets: dict[str, AutoPoseSet],
                   gaits: dict[str, Gait], directory: Path, on_ready: Callable[[str], None] | None) -> RunResult:
    """A physics engine: the robot simulated in real time, its measured joints, IMU, foot forces and power published
    (``/joint_states``, ``/imu/data``, ``/<LEG>/foot_force``, ``/shc/power``) — OpenSHC's Gazebo set-up without
    Gazebo. The engine's options are ``shc simulate``'s defaults for the robot (flat ground, 400 Hz)."""
    from shc_cli.loop.assembly import assemble

    def build(parts: Assembly) -> RunSpec[Reading]:
        from shc_cli.backends.simulated import SimulatedBackend, open_world
        from shc_cli.control.controller import Controller
        from shc_cli.control.verified_limits import source_for
        from shc_cli.domain.config import SimulationConfig
        from shc_cli.domain.ros_session import NodeSession
        from shc_cli.loop.assembly import RunSpec
        from shc_cli.loop.physics_summary import PhysicsRecord
        from shc_cli.record.runlog import LogRecorder, RunDirectory

        sim = SimulationConfig(robot=config.robot, engine=config.backend)
        run = parts.enter(RunDirectory(directory, config.overwrite))
        world = open_world(robot, sim.engine_options(robot))
        backend = parts.enter(SimulatedBackend(robot, world))
        controller = Controller(robot, gait, joints=backend.start(), pose_sets=pose_sets,
                                speed_shares=source_for(robot))
        run.write_robot(robot)
        record = PhysicsRecord(robot, backend, sim.airborne)
        session = NodeSession(node, config, robot, controller, gaits, sensors=True)
        stream = live_observer(parts, config.live, config.live_port, robot, controller, sensors=True)
        path_fields = session.keep_path(run.partial)
        session.ready(node, config, robot, gait, on_ready)

        def summarise(finished: Finished) -> RunSummary:
            return record.summary(finished.directory, sim.scenario, controller.gait.name, controller, {
                "cycles": record.cycles, "engine": world.name, "engine_version": world.version,
                "engine_warnings": world.warnings, "backend": config.backend, "ros_master": node.master_uri,
                "node": node.name, **finished.shared}, ("simulate", "ros"))

        return RunSpec(controller, backend, session.source, LogRecorder(run, robot, backend), None, run, summarise,
                       observers=[record, session.outputs], live=stream, pacing=session.clock,
                       late_observers=[session.deadline], path_fields=path_fields, on_loop=session.watch,
                       flush_every=100)

    return RunResult(*assemble(build).pair)
