"""Reading a bag written by ``shc export bag`` back as the run it was written from (a :class:`RunLog`).

Between the bag format (:mod:`shc_cli.interop.bag`) and the run reader (:mod:`shc_cli.record.runread`); opened through
:func:`shc_cli.domain.stored_run.open_run`.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from shc_cli.model.chains import joint_slots
from shc_cli.record.runread import RunLog, bad_run, checked_summary


def read_bag_run(path: Path) -> RunLog:
    """A bag from ``shc export bag`` (ROS 2 directory or ROS 1 file) as the run it was written from."""
    import tempfile

    from shc_cli.analysis.metrics import rpy_of
    from shc_cli.control.sensing import quaternion_matrix
    from shc_cli.errors import SpecError
    from shc_cli.interop.bag import ROBOT_STATES, WALK_STATES, read_topics
    from shc_cli.spec.loading import load_robot

    topics = read_topics(path)
    if "/shc/robot" not in topics or "/shc/state" not in topics:
        raise bad_run(path, "a bag without shc's /shc/robot and /shc/state topics", "export it with shc export bag")
    summary = checked_summary(path, json.loads(topics["/shc/summary"][0][1].data))
    with tempfile.TemporaryDirectory() as directory:
        robot_file = Path(directory) / "robot.toml"
        robot_file.write_text(topics["/shc/robot"][0][1].data, encoding="utf-8")
        try:
            loaded = load_robot(robot_file).robot
        except SpecError as error:  # the bag's /shc/robot, not the temporary file it was read through, is at fault
            raise bad_run(path, f"its /shc/robot does not load ({str(error).split(': ', 2)[-1]})",
                          "re-export it") from None
    if loaded is None:
        raise bad_run(path, "its /shc/robot does not load", "re-export it")
    robot = loaded
    legs = list(robot.legs)
    width = max(len(leg.joints) for leg in robot.legs.values())
    rows_, cols_ = joint_slots(robot)

    def joint_array(topic: str, field: str) -> np.ndarray:
        values = np.array([getattr(m, field) for _, m in topics[topic]])
        out = np.zeros((len(values), len(legs), width))
        out[:, rows_, cols_] = values
        return out

    stamps = np.array([stamp for stamp, _ in topics["/joint_states"]], dtype=np.int64)
    estimated = None
    if "/ground_truth/odom" in topics:  # since the leg odometry: /odom is the estimate, the truth is apart
        estimate = [m.pose.pose for _, m in topics["/odom"]]
        estimated = np.array([[p.position.x, p.position.y, 0.0] for p in estimate])
        estimated[:, 2] = np.unwrap(rpy_of(quaternion_matrix(np.array(
            [[p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w] for p in estimate])))[:, 2])
        odom = [m for _, m in topics["/ground_truth/odom"]]
    else:
        odom = [m for _, m in topics["/odom"]]
    position = np.array([[o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z] for o in odom])
    quaternion = np.array([[o.pose.pose.orientation.x, o.pose.pose.orientation.y, o.pose.pose.orientation.z,
                            o.pose.pose.orientation.w] for o in odom])
    rotation = quaternion_matrix(quaternion)
    linear = np.array([[o.twist.twist.linear.x, o.twist.twist.linear.y, o.twist.twist.linear.z] for o in odom])
    angular = np.array([[o.twist.twist.angular.x, o.twist.twist.angular.y, o.twist.twist.angular.z] for o in odom])
    state = np.array([m.data for _, m in topics["/shc/state"]])
    robot_names = {v: k for k, v in ROBOT_STATES.items()}
    walk_names = {v: k for k, v in WALK_STATES.items()}
    states = np.array([[robot_names[int(r)], walk_names[int(w)]] for r, w in state[:, :2]])
    command = np.array([[m.linear.x, m.linear.y, m.angular.z] for _, m in topics["/cmd_vel"]])
    simulated = "/shc/power" in topics
    forces = np.stack([[m.wrench.force.z for _, m in topics[f"/{leg}/foot_force"]] for leg in legs], axis=1) \
        if simulated else None
    leg_states = [[m for _, m in topics[f"/shc/{leg}/state"]] for leg in legs]
    progress = np.array([[[m.stance_progress, m.swing_progress] for m in per_leg] for per_leg in leg_states])
    progress = progress.transpose(1, 0, 2)
    joints = joint_array("/joint_states", "position")
    height = state[:, 2]
    if simulated:
        imu = [m for _, m in topics["/imu/data"]]
        contact = np.asarray(forces) > 0.0
    else:
        contact = progress[:, :, 0] >= 0.0
    return RunLog(
        path=path, kind="simulate" if simulated else "plan", summary=summary, robot=robot, t=stamps / 1e9,
        running=states[:, 0] == "RUNNING", walk_state=states[:, 1], command=command, desired=state[:, 3:6],
        position=position, rpy=rpy_of(rotation), joints=joints, contact=contact,
        power=np.array([m.data for _, m in topics["/shc/power"]]) if simulated else None, foot_force=forces,
        body_rate=np.array([[m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z] for m in imu])
        if simulated else None,
        height=height, commanded=joint_array("/desired_joint_states", "position"),
        efforts=joint_array("/joint_states", "effort") if simulated else None,
        twist=np.hstack([np.einsum("nij,nj->ni", rotation, linear), np.einsum("nij,nj->ni", rotation, angular)])
        if simulated else None,
        imu=np.array([[m.orientation.x, m.orientation.y, m.orientation.z, m.orientation.w, m.angular_velocity.x,
                       m.angular_velocity.y, m.angular_velocity.z, m.linear_acceleration.x, m.linear_acceleration.y,
                       m.linear_acceleration.z] for m in imu]) if simulated else None,
        progress=None if simulated else progress, states=states, odometry=estimated,
    )

