"""A run directory as a ROS bag (ROS 2 mcap or sqlite3, or ROS 1), written with ``rosbags`` — no ROS install.

Topics (stamps = run time from 0; frames as in the generated URDF, ``shc export urdf``):

| topic | type | content |
|---|---|---|
| ``/robot_description`` | std_msgs/String | the generated URDF, once at the start |
| ``/tf_static`` | tf2_msgs/TFMessage | ``base_link → LEG_base`` (the legs' DH base frames), once |
| ``/tf`` | tf2_msgs/TFMessage | ``odom → base_link`` (odometry); ``base_link →`` each ``LEG_J_link``, ``LEG_foot``|
| ``/joint_states`` | sensor_msgs/JointState | measured positions, velocity by differences, efforts; plan: commanded |
| ``/desired_joint_states`` | sensor_msgs/JointState | commanded positions and their differences |
| ``/cmd_vel`` | geometry_msgs/Twist | the velocity input (x, y, yaw) |
| ``/odom`` | nav_msgs/Odometry | the controller's leg odometry in ``odom``, its velocity in ``base_link`` |
| ``/ground_truth/odom`` | nav_msgs/Odometry | true body pose in ``world`` (plan: ideal path), its velocity |
| ``/imu/data`` | sensor_msgs/Imu | orientation, angular rate, specific force (simulate) |
| ``/LEG/foot_force`` | geometry_msgs/WrenchStamped | contact normal force along z of ``LEG_foot`` (simulate) |
| ``/shc/LEG/state`` | syropod_highlevel_controller/LegState | OpenSHC's per-leg record (fields below) |
| ``/shc/power`` | std_msgs/Float64 | total electrical power [W] (simulate) |
| ``/shc/state`` | std_msgs/Float64MultiArray | robot and walk state (OpenSHC values), height [m], desired velocity |
| ``/shc/robot``, ``/shc/summary`` | std_msgs/String | the run's expanded robot TOML and summary JSON, once |
| ``/shc/servo_map`` | std_msgs/String | with ``[hardware.servos]``: per joint its bus, id, model, direction, zero |

Joint names: a robot whose ``[hardware.servos]`` names its joints (``joint = "j_c1_rf"``: an imported URDF's names)
is written with those names in ``/joint_states``, ``/desired_joint_states`` and the joints of ``/robot_description``
— as the robot's own driver publishes them, so the bag plays beside the maker's description and recordings — and
``/shc/servo_map`` ties each name to its servo; other joints keep OpenSHC's ``AR_coxa_joint``. Links and ``/tf``
frames keep the generated URDF's names.

LegState (OpenSHC's ``LegState.msg``, registered in the bag): ``walker_tip_pose``, ``poser_tip_pose`` (plan),
``model_tip_pose`` (forward kinematics of the commanded joints), ``actual_tip_pose`` (of the measured joints),
joint positions/velocities/efforts, stance and swing progress (plan; −1 otherwise); the other fields are zero.

The leg odometry (docs/odometry.md) is planar: ``/odom`` and the ``odom → base_link`` transform carry its x, y and
yaw with the body's logged height, roll and pitch (the engine's in simulate, the commanded pose in plan), so the
robot stands on the ground in a 3-D view. A run logged before the odometry columns existed has no odometry: its
``/odom`` and ``odom → base_link`` are then the true pose, as they were, and there is no ``/ground_truth/odom``.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from shc_cli.control.states import RobotState, WalkState
from shc_cli.errors import OutputError, check_choice
from shc_cli.interop import mcap_chunks
from shc_cli.interop.batch import BatchSerializer
from shc_cli.model.chains import joint_slots
from shc_cli.record.runlog import ROBOT_FILE
from shc_cli.record.runread import RunLog

if TYPE_CHECKING:
    from shc_cli.model.chains import Chains
    from shc_cli.spec.robot import Robot

FORMATS = ("mcap", "sqlite3", "ros1")
ROBOT_STATES = {state.name: int(state) for state in RobotState}
"""OpenSHC's robot-state values (``/shc/state`` data[0])."""
WALK_STATES = {state.name: int(state) for state in WalkState}
"""OpenSHC's walk-state values (``/shc/state`` data[1])."""
LEG_STATE_TYPE = "syropod_highlevel_controller/msg/LegState"
LEG_STATE_MSG = """std_msgs/Header header
string name
geometry_msgs/PoseStamped walker_tip_pose
geometry_msgs/PoseStamped target_tip_pose
geometry_msgs/PoseStamped poser_tip_pose
geometry_msgs/PoseStamped model_tip_pose
geometry_msgs/PoseStamped actual_tip_pose
geometry_msgs/TwistStamped model_tip_velocity
float64[] joint_positions
float64[] joint_velocities
float64[] joint_efforts
float64 stance_progress
float64 swing_progress
float64 time_to_swing_end
geometry_msgs/Pose pose_delta
geometry_msgs/Pose auto_pose
geometry_msgs/Vector3 tip_force
geometry_msgs/Vector3 admittance_delta
float64 virtual_stiffness
"""
"""OpenSHC's LegState.msg (``shared/reference/openshc/LegState.msg``), field for field."""


def typestore_for(fmt: str) -> Any:
    """The rosbags typestore of the format (ROS 2 Humble or ROS 1 Noetic) with LegState registered."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC if fmt == "ros1" else Stores.ROS2_HUMBLE)
    types = get_types_from_msg(LEG_STATE_MSG, LEG_STATE_TYPE)
    if "tf2_msgs/msg/TFMessage" not in store.types:  # rosbags' Noetic store has no tf2_msgs
        types.update(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"))
    store.register(types)
    return store


def read_topics(path: Path) -> dict[str, list[tuple[int, Any]]]:
    """Every message of a bag (ROS 2 directory or ROS 1 ``.bag`` file), deserialised, by topic, in time order."""
    ros1 = path.is_file()
    store = typestore_for("ros1" if ros1 else "mcap")
    out: dict[str, list[tuple[int, Any]]] = {}
    if ros1:
        from rosbags.rosbag1 import Reader as Reader1

        with Reader1(path) as reader:
            for connection, stamp, raw in reader.messages():
                out.setdefault(connection.topic, []).append((stamp, store.deserialize_ros1(raw, connection.msgtype)))
    else:
        from rosbags.rosbag2 import Reader

        with Reader(path) as reader:
            for connection, stamp, raw in reader.messages():
                out.setdefault(connection.topic, []).append((stamp, store.deserialize_cdr(raw, connection.msgtype)))
    return out


def quaternions(rotations: np.ndarray) -> np.ndarray:
    """Unit quaternions (x, y, z, w), w ≥ 0, of rotation matrices ``(..., 3, 3)`` (Shepperd's method: each row uses
    the largest of the four possible denominators)."""
    shape = rotations.shape[:-2]
    m = rotations.reshape(-1, 3, 3)
    m00, m11, m22 = m[:, 0, 0], m[:, 1, 1], m[:, 2, 2]
    trace = m00 + m11 + m22
    candidates = np.stack([trace, m00, m11, m22], axis=1)
    pick = np.argmax(candidates, axis=1)
    out = np.empty((len(m), 4))
    for case in range(4):
        rows = pick == case
        if not rows.any():
            continue
        r = m[rows]
        if case == 0:
            s = 2.0 * np.sqrt(1.0 + trace[rows])
            out[rows] = np.stack([(r[:, 2, 1] - r[:, 1, 2]) / s, (r[:, 0, 2] - r[:, 2, 0]) / s,
                                  (r[:, 1, 0] - r[:, 0, 1]) / s, 0.25 * s], axis=1)
        elif case == 1:
            s = 2.0 * np.sqrt(1.0 + r[:, 0, 0] - r[:, 1, 1] - r[:, 2, 2])
            out[rows] = np.stack([0.25 * s, (r[:, 0, 1] + r[:, 1, 0]) / s, (r[:, 0, 2] + r[:, 2, 0]) / s,
                                  (r[:, 2, 1] - r[:, 1, 2]) / s], axis=1)
        elif case == 2:
            s = 2.0 * np.sqrt(1.0 + r[:, 1, 1] - r[:, 0, 0] - r[:, 2, 2])
            out[rows] = np.stack([(r[:, 0, 1] + r[:, 1, 0]) / s, 0.25 * s, (r[:, 1, 2] + r[:, 2, 1]) / s,
                                  (r[:, 0, 2] - r[:, 2, 0]) / s], axis=1)
        else:
            s = 2.0 * np.sqrt(1.0 + r[:, 2, 2] - r[:, 0, 0] - r[:, 1, 1])
            out[rows] = np.stack([(r[:, 0, 2] + r[:, 2, 0]) / s, (r[:, 1, 2] + r[:, 2, 1]) / s, 0.25 * s,
                                  (r[:, 1, 0] - r[:, 0, 1]) / s], axis=1)
    out /= np.linalg.norm(out, axis=1, keepdims=True)
    out[out[:, 3] < 0.0] *= -1.0
    return out.reshape(*shape, 4)


class Messages:
    """Message constructors of one typestore (ROS 1 headers carry a ``seq``)."""

    def __init__(self, store: Any) -> None:
        self.T = store.types
        self.ros1 = "seq" in self.T["std_msgs/msg/Header"].__dataclass_fields__

    def header(self, sec: int, nanosec: int, frame: str) -> Any:
        T = self.T
        stamp = T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec)
        if self.ros1:
            return T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame)
        return T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    def vector(self, v: np.ndarray) -> Any:
        return self.T["geometry_msgs/msg/Vector3"](x=float(v[0]), y=float(v[1]), z=float(v[2]))

    def point(self, v: np.ndarray) -> Any:
        return self.T["geometry_msgs/msg/Point"](x=float(v[0]), y=float(v[1]), z=float(v[2]))

    def quaternion(self, q: np.ndarray) -> Any:
        return self.T["geometry_msgs/msg/Quaternion"](x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3]))

    def pose(self, v: np.ndarray) -> Any:
        """Pose from 7 numbers (position, quaternion x y z w)."""
        return self.T["geometry_msgs/msg/Pose"](position=self.point(v[:3]), orientation=self.quaternion(v[3:7]))

    def transform(self, sec: int, nanosec: int, parent: str, child: str, v: np.ndarray) -> Any:
        T = self.T
        return T["geometry_msgs/msg/TransformStamped"](
            header=self.header(sec, nanosec, parent), child_frame_id=child,
            transform=T["geometry_msgs/msg/Transform"](translation=self.vector(v[:3]),
                                                       rotation=self.quaternion(v[3:7])))


def _serialize_as(serialize: Callable[[Any, str], bytes], msgtype: str, message: Any) -> bytes:
    return serialize(message, msgtype)


def _renamed_joints(urdf: str, names: dict[str, str]) -> str:
    """The generated URDF with its joints named as ``/joint_states`` names them (links and frames unchanged)."""
    for old, new in names.items():
        if old != new:
            urdf = urdf.replace(f'<joint name="{old}"', f'<joint name="{new}"')
    return urdf


def servo_map(robot: Robot, names: list[str]) -> dict[str, dict[str, Any]]:
    """``/shc/servo_map``: per joint (by its ``/joint_states`` name) the robot file's key and its servo — bus, id,
    model, direction, zero_ticks (None: the middle of the model's range) — as ``[hardware.servos]`` gives them."""
    keys = [f"{leg}_{joint}" for leg, spec in robot.legs.items() for joint in spec.joints]
    hardware = robot.hardware
    out: dict[str, dict[str, Any]] = {}
    for name, key in zip(names, keys, strict=True):
        servo = hardware.servos.get(key)
        if servo is not None:
            out[name] = {"key": key, "bus": servo.bus, "id": servo.id, "model": servo.model or hardware.model,
                         "direction": servo.direction, "zero_ticks": servo.zero_ticks}
    return out


def _differences(values: np.ndarray, dt: float) -> np.ndarray:
    """Backward differences per cycle (0 for the first) [unit/s]."""
    out = np.zeros_like(values)
    out[1:] = (values[1:] - values[:-1]) / dt
    return out


def default_bag_path(run: Path, fmt: str) -> Path:
    """Where ``shc export bag RUN`` writes a bag of ``fmt`` without ``--out``: ``RUN_bag`` (mcap),
    ``RUN_bag_sqlite3`` (sqlite3), ``RUN.bag`` (ros1) — one name per format, so exporting a second format does not
    collide with the first."""
    suffix = {"ros1": ".bag", "sqlite3": "_bag_sqlite3"}.get(fmt, "_bag")
    return run.with_name(run.name + suffix)


def check_bag_out(out: Path, fmt: str, overwrite: bool) -> None:
    """The output rule for a bag at ``out`` (one line, before any work): a ROS 2 bag (mcap, sqlite3) is a folder,
    so ``out`` must not name a file (``runs/arc.mcap``); a ROS 1 bag is a ``.bag`` file; an existing output only
    with ``overwrite``, and then only a bag (shc replaces nothing else)."""
    from shc_cli.outputs import refuse_existing, refuse_file_like

    check_choice("--format", fmt, FORMATS, "a bag format")
    if fmt == "ros1":
        if out.suffix != ".bag":
            raise OutputError(f"{out}: --format ros1 writes one .bag file; give --out NAME.bag")
    else:
        refuse_file_like(out, f"a ROS 2 bag (metadata.yaml and its .{'mcap' if fmt == 'mcap' else 'db3'} data file)",
                         out.with_suffix(""))
    refuse_existing([out], overwrite)
    if out.exists() and not _is_bag(out):
        raise OutputError(f"{out}: exists and is not a bag, so --overwrite does not replace it (choose another --out)")


def _is_bag(path: Path) -> bool:
    return (path.is_dir() and (path / "metadata.yaml").is_file()) or (path.is_file() and path.suffix == ".bag")


def export_bag(run: RunLog, out: Path, fmt: str, overwrite: bool = False) -> Path:
    """Write ``run`` as a bag at ``out`` (a directory for ROS 2 formats, a ``.bag`` file for ROS 1), atomically; an
    existing bag there is replaced (when the new one is complete) only with ``overwrite`` (:func:`check_bag_out`)."""
    check_bag_out(out, fmt, overwrite)
    # Written under a hidden .partial folder and moved into place when complete; inside it the bag keeps its final
    # name, because rosbags names a ROS 2 bag's data file after its directory.
    staging = out.with_name(f".{out.name}.partial")
    if staging.exists():
        shutil.rmtree(staging)
    staging.mkdir(parents=True)
    temporary = staging / out.name
    store = typestore_for(fmt)
    serialize: Callable[[Any, str], bytes] = store.serialize_ros1 if fmt == "ros1" else store.serialize_cdr
    topics = _topics(run, Messages(store))
    if fmt == "ros1":
        from rosbags.rosbag1 import Writer as Writer1

        writer: Any = Writer1(temporary)
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer

        plugin = StoragePlugin.MCAP if fmt == "mcap" else StoragePlugin.SQLITE3
        writer = Writer(temporary, version=9, storage_plugin=plugin)
    stamps = np.round(run.t * 1e9).astype(np.int64)
    with writer:
        streams = []
        for topic, msgtype, build, width, values, once in topics:
            connection = writer.add_connection(topic, msgtype, typestore=store)
            if once:
                writer.write(connection, int(stamps[0]), bytes(serialize(build(0, 0, np.zeros(0)), msgtype)))
                continue
            batch = BatchSerializer(partial(_serialize_as, serialize, msgtype), build, width)
            streams.append((connection, batch.serialize(stamps, values)))
        if fmt == "mcap" and mcap_chunks.supports(writer):
            if writer.storage.chunk.bio.tell():
                writer.storage.close_chunk()  # channels and the once-only messages first
            mcap_chunks.write_streams(writer, streams, stamps)
        else:
            for row, stamp in enumerate(stamps.tolist()):  # time order, as a recorder writes
                for connection, data in streams:
                    writer.write(connection, stamp, data[row].tobytes())
    if out.is_dir():
        shutil.rmtree(out)  # --overwrite of a bag folder (check_bag_out): the new bag is complete
    temporary.replace(out)
    staging.rmdir()
    return out


Topic = tuple[str, str, Callable[[int, int, np.ndarray], Any], int, np.ndarray, bool]


def _topics(run: RunLog, m: Messages) -> list[Topic]:
    """Every topic: (name, type, builder, numbers per message, numbers ``(N, width)``, written once)."""
    from shc_cli.analysis.metrics import rotation_rpy
    from shc_cli.backends.pybullet_.urdf import robot_urdf
    from shc_cli.model.body import hardware_joint_names, leg_names
    from shc_cli.model.chains import Chains

    T = m.T
    robot = run.robot
    n = len(run.t)
    dt = run.dt
    legs = list(robot.legs)
    names = leg_names(robot)
    chains = Chains.from_robot(robot)
    rows_, cols_ = joint_slots(robot)
    generated = [joint for leg in names.values() for joint in leg.joints]
    joint_ids = hardware_joint_names(robot)  # as the robot's own driver names them (the servo map's), if it says
    measured = run.joints[:, rows_, cols_]
    commanded = (run.commanded if run.commanded is not None else run.joints)[:, rows_, cols_]
    efforts = run.efforts[:, rows_, cols_] if run.efforts is not None else np.zeros_like(measured)
    count = len(joint_ids)
    topics: list[Topic] = []

    def joint_state(sec: int, nanosec: int, v: np.ndarray) -> Any:
        return T["sensor_msgs/msg/JointState"](header=m.header(sec, nanosec, ""), name=joint_ids,
                                               position=v[:count].copy(), velocity=v[count:2 * count].copy(),
                                               effort=v[2 * count:].copy())

    topics.append(("/joint_states", "sensor_msgs/msg/JointState", joint_state, 3 * count,
                   np.hstack([measured, _differences(measured, dt), efforts]), False))
    topics.append(("/desired_joint_states", "sensor_msgs/msg/JointState", joint_state, 3 * count,
                   np.hstack([commanded, _differences(commanded, dt), np.zeros_like(commanded)]), False))

    urdf = _renamed_joints(robot_urdf(robot), dict(zip(generated, joint_ids, strict=True)))
    def description(sec: int, nanosec: int, v: np.ndarray) -> Any:
        return T["std_msgs/msg/String"](data=urdf)

    topics.append(("/robot_description", "std_msgs/msg/String", description, 0, np.zeros((n, 0)), True))
    base_q = quaternions(chains.base[:, :3, :3])
    static = [np.concatenate([chains.base[i, :3, 3], base_q[i]]) for i in range(len(legs))]
    topics.append(("/tf_static", "tf2_msgs/msg/TFMessage",
                   lambda s, ns, v: T["tf2_msgs/msg/TFMessage"](transforms=[
                       m.transform(0, 0, "base_link", names[leg].base, static[i]) for i, leg in enumerate(legs)]),
                   0, np.zeros((n, 0)), True))

    # /tf: odom → base_link, base_link → every joint link (DH frame k turned by q_k) and foot (the DH tip).
    body_rotation = rotation_rpy(run.rpy)
    body = np.hstack([run.position, quaternions(body_rotation)])
    if run.odometry is not None:  # the odometry's x, y, yaw with the body's height, roll and pitch
        odometry_rotation = rotation_rpy(np.column_stack([run.rpy[:, :2], run.odometry[:, 2]]))
        estimate = np.hstack([run.odometry[:, :2], run.position[:, 2:3], quaternions(odometry_rotation)])
    else:
        odometry_rotation, estimate = body_rotation, body
    frames = chains.frames_in_base(run.joints)
    links: list[tuple[str, np.ndarray]] = []
    for i, leg in enumerate(legs):
        for k, link in enumerate(names[leg].links):
            q = run.joints[:, i, k]
            turn = np.zeros((n, 4, 4))
            turn[:, 0, 0], turn[:, 0, 1], turn[:, 1, 0], turn[:, 1, 1] = np.cos(q), -np.sin(q), np.sin(q), np.cos(q)
            turn[:, 2, 2] = turn[:, 3, 3] = 1.0
            links.append((link, frames[:, i, k] @ turn))
        links.append((names[leg].foot, frames[:, i, len(names[leg].links)]))
    tf_values = [estimate] + [np.hstack([matrix[:, :3, 3], quaternions(matrix[:, :3, :3])]) for _, matrix in links]
    child_names = ["base_link"] + [name for name, _ in links]

    def tf(sec: int, nanosec: int, v: np.ndarray) -> Any:
        return T["tf2_msgs/msg/TFMessage"](transforms=[
            m.transform(sec, nanosec, "odom" if j == 0 else "base_link", child, v[7 * j:7 * j + 7])
            for j, child in enumerate(child_names)])

    topics.append(("/tf", "tf2_msgs/msg/TFMessage", tf, 7 * len(child_names), np.hstack(tf_values), False))

    def twist(s: int, ns: int, v: np.ndarray) -> Any:
        return T["geometry_msgs/msg/Twist"](linear=m.vector(np.array([v[0], v[1], 0.0])),
                                            angular=m.vector(np.array([0.0, 0.0, v[2]])))

    topics.append(("/cmd_vel", "geometry_msgs/msg/Twist", twist, 3, run.command, False))

    # shc's own records, so that `shc analyze` reads a bag as it reads the run directory.
    robot_text = (run.path / ROBOT_FILE).read_text(encoding="utf-8") if (run.path / ROBOT_FILE).exists() else ""
    summary_text = json.dumps(run.summary.model_dump(mode="json", exclude_unset=True))
    topics.append(("/shc/robot", "std_msgs/msg/String", lambda s, ns, v: T["std_msgs/msg/String"](data=robot_text),
                   0, np.zeros((n, 0)), True))
    topics.append(("/shc/summary", "std_msgs/msg/String",
                   lambda s, ns, v: T["std_msgs/msg/String"](data=summary_text), 0, np.zeros((n, 0)), True))
    if robot.hardware.servos:
        servo_text = json.dumps(servo_map(robot, joint_ids))
        topics.append(("/shc/servo_map", "std_msgs/msg/String",
                       lambda s, ns, v: T["std_msgs/msg/String"](data=servo_text), 0, np.zeros((n, 0)), True))
    states = run.states if run.states is not None else np.full((n, 2), "UNKNOWN")
    robot_codes = np.array([ROBOT_STATES.get(str(x), -1) for x in states[:, 0]], dtype=float)
    walk_codes = np.array([WALK_STATES.get(str(x), 3) for x in states[:, 1]], dtype=float)
    height = run.height if run.height is not None else np.full(n, np.nan)

    def state(sec: int, nanosec: int, v: np.ndarray) -> Any:
        layout = T["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0)
        return T["std_msgs/msg/Float64MultiArray"](layout=layout, data=v.copy())

    topics.append(("/shc/state", "std_msgs/msg/Float64MultiArray", state, 6,
                   np.column_stack([robot_codes, walk_codes, height, run.desired]), False))

    world_twist = run.twist if run.twist is not None else np.hstack([
        _differences(run.position, dt), np.zeros((n, 2)), _differences(np.unwrap(run.rpy[:, 2]), dt)[:, None]])
    body_linear = np.einsum("nji,nj->ni", body_rotation, world_twist[:, :3])  # Rᵀ·v: base_link axes
    body_angular = np.einsum("nji,nj->ni", body_rotation, world_twist[:, 3:])

    def odometry(sec: int, nanosec: int, v: np.ndarray) -> Any:
        return T["nav_msgs/msg/Odometry"](
            header=m.header(sec, nanosec, "odom"), child_frame_id="base_link",
            pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=m.pose(v[:7]), covariance=np.zeros(36)),
            twist=T["geometry_msgs/msg/TwistWithCovariance"](
                twist=T["geometry_msgs/msg/Twist"](linear=m.vector(v[7:10]), angular=m.vector(v[10:13])),
                covariance=np.zeros(36)))

    if run.odometry is None:
        topics.append(("/odom", "nav_msgs/msg/Odometry", odometry, 13, np.hstack([body, body_linear, body_angular]),
                       False))
    else:
        def truth(sec: int, nanosec: int, v: np.ndarray) -> Any:
            message = odometry(sec, nanosec, v)
            message.header.frame_id = "world"
            return message

        topics.append(("/ground_truth/odom", "nav_msgs/msg/Odometry", truth, 13,
                       np.hstack([body, body_linear, body_angular]), False))
        planar = np.column_stack([run.odometry[:, :2], np.unwrap(run.odometry[:, 2])])
        rates = _differences(planar, dt)
        odometry_linear = np.einsum("nji,nj->ni", odometry_rotation,
                                    np.column_stack([rates[:, :2], np.zeros(n)]))
        odometry_angular = np.column_stack([np.zeros((n, 2)), rates[:, 2]])
        topics.append(("/odom", "nav_msgs/msg/Odometry", odometry, 13,
                       np.hstack([estimate, odometry_linear, odometry_angular]), False))

    if run.imu is not None:
        def imu(sec: int, nanosec: int, v: np.ndarray) -> Any:
            return T["sensor_msgs/msg/Imu"](
                header=m.header(sec, nanosec, "base_link"), orientation=m.quaternion(v[:4]),
                orientation_covariance=np.zeros(9), angular_velocity=m.vector(v[4:7]),
                angular_velocity_covariance=np.zeros(9), linear_acceleration=m.vector(v[7:10]),
                linear_acceleration_covariance=np.zeros(9))

        topics.append(("/imu/data", "sensor_msgs/msg/Imu", imu, 10, run.imu, False))
    if run.foot_force is not None:
        for i, leg in enumerate(legs):
            def wrench(sec: int, nanosec: int, v: np.ndarray, frame: str = names[leg].foot) -> Any:
                return T["geometry_msgs/msg/WrenchStamped"](
                    header=m.header(sec, nanosec, frame),
                    wrench=T["geometry_msgs/msg/Wrench"](force=m.vector(np.array([0.0, 0.0, v[0]])),
                                                         torque=m.vector(np.zeros(3))))

            topics.append((f"/{leg}/foot_force", "geometry_msgs/msg/WrenchStamped", wrench, 1,
                           run.foot_force[:, i:i + 1], False))
    if run.power is not None:
        topics.append(("/shc/power", "std_msgs/msg/Float64", lambda s, ns, v: T["std_msgs/msg/Float64"](
            data=float(v[0])), 1, run.power[:, None], False))
    actual = frames[:, :, -1, :3, 3]  # the measured joints' tips
    topics += _leg_states(run, m, chains, legs, measured, commanded, efforts, rows_, actual)
    return topics


def _leg_states(run: RunLog, m: Messages, chains: Chains, legs: list[str], measured: np.ndarray,
                commanded: np.ndarray, efforts: np.ndarray, leg_of_slot: np.ndarray, actual: np.ndarray) -> list[Topic]:
    """One LegState topic per leg (``/shc/LEG/state``)."""
    T = m.T
    n = len(run.t)
    identity_q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    commanded_full = run.commanded if run.commanded is not None else run.joints
    model = chains.frames_in_base(commanded_full)[:, :, -1, :3, 3] if run.commanded is not None else actual
    zeros3 = np.zeros((n, 3))
    dt = run.dt
    out: list[Topic] = []
    for i, leg in enumerate(legs):
        slots = np.flatnonzero(leg_of_slot == i)
        joints = len(slots)
        walker = run.tips[:, i, 0] if run.tips is not None else zeros3
        poser = run.tips[:, i, 1] if run.tips is not None else zeros3
        progress = run.progress[:, i] if run.progress is not None else np.full((n, 2), -1.0)
        values = np.hstack([walker, identity_q, zeros3, identity_q, poser, identity_q, model[:, i], identity_q,
                            actual[:, i], identity_q, measured[:, slots], _differences(measured[:, slots], dt),
                            efforts[:, slots], progress])

        def leg_state(sec: int, nanosec: int, v: np.ndarray, name: str = leg, count: int = joints) -> Any:
            def stamped(j: int, frame: str) -> Any:
                return T["geometry_msgs/msg/PoseStamped"](header=m.header(sec, nanosec, frame),
                                                          pose=m.pose(v[7 * j:7 * j + 7]))

            at = 35
            zero = T["geometry_msgs/msg/Pose"](position=m.point(np.zeros(3)), orientation=m.quaternion(
                np.array([0.0, 0.0, 0.0, 1.0])))
            return T[LEG_STATE_TYPE](
                header=m.header(sec, nanosec, "base_link"), name=name,
                walker_tip_pose=stamped(0, "walk_plane"), target_tip_pose=stamped(1, "walk_plane"),
                poser_tip_pose=stamped(2, "base_link"), model_tip_pose=stamped(3, "base_link"),
                actual_tip_pose=stamped(4, "base_link"),
                model_tip_velocity=T["geometry_msgs/msg/TwistStamped"](
                    header=m.header(sec, nanosec, "base_link"),
                    twist=T["geometry_msgs/msg/Twist"](linear=m.vector(np.zeros(3)), angular=m.vector(np.zeros(3)))),
                joint_positions=v[at:at + count].copy(), joint_velocities=v[at + count:at + 2 * count].copy(),
                joint_efforts=v[at + 2 * count:at + 3 * count].copy(), stance_progress=float(v[at + 3 * count]),
                swing_progress=float(v[at + 3 * count + 1]), time_to_swing_end=0.0, pose_delta=zero, auto_pose=zero,
                tip_force=m.vector(np.zeros(3)), admittance_delta=m.vector(np.zeros(3)), virtual_stiffness=0.0)

        out.append((f"/shc/{leg}/state", LEG_STATE_TYPE, leg_state, values.shape[1], values, False))
    return out
