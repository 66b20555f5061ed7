"""A ROS 2 remote and recorder written with plain rclpy and rosbags (not shc's node): records a ``shc ros2`` session
as a ROS 2 bag, as ``ros2 bag record`` would (which is not on PyPI).

``python tests/ros2_bag_recorder.py BAG SCALE``: subscribes (raw CDR bytes, reliable) the node's
``/desired_joint_states``, ``/shc/velocity``, ``/shc/pose`` and the remote's ``/syropod_remote/desired_velocity`` and
``/syropod_remote/robot_state``, writing every message with the time the middleware received it into the rosbag2
directory BAG (mcap);
as a remote it publishes OPERATIONAL and RUNNING at 10 Hz, and once the node is RUNNING (its first
``/shc/walkspace``) the insectoid recording's velocity schedule shortened by SCALE, each change published from the
callback of a ``/desired_joint_states`` message and counted in them (as ``tests/ros_remote_driver.py`` does on
ROS 1). Ends when the schedule is done. ROS_DOMAIN_ID and ROS_AUTOMATIC_DISCOVERY_RANGE come from the environment.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Any

SEGMENTS = [(0.5, 0.0, 0.0, 20.0), (1.0, 0.0, 0.0, 20.0), (0.0, 0.0, 0.0, 5.0), (0.0, 0.0, 0.5, 20.0),
            (0.0, 0.0, 0.0, 5.0)]
"""The recording's segments: vx, vy, wz (throttle fractions), duration [s]."""
TOPICS = {"/desired_joint_states": "sensor_msgs/msg/JointState", "/shc/velocity": "geometry_msgs/msg/Twist",
          "/shc/pose": "geometry_msgs/msg/Twist", "/syropod_remote/desired_velocity": "geometry_msgs/msg/Twist",
          "/syropod_remote/robot_state": "std_msgs/msg/Int8"}


def main() -> None:
    bag, scale = Path(sys.argv[1]), float(sys.argv[2])
    import rclpy
    from geometry_msgs.msg import Twist
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float32MultiArray, Int8

    classes: dict[str, Any] = {"sensor_msgs/msg/JointState": JointState, "geometry_msgs/msg/Twist": Twist,
                               "std_msgs/msg/Int8": Int8}
    store = get_typestore(Stores.ROS2_KILTED)
    schedule: list[tuple[float, float, float]] = []
    for vx, vy, wz, seconds in SEGMENTS:
        schedule += [(vx, vy, wz)] * max(1, round(seconds * scale * 100))
    rclpy.init()
    node = rclpy.create_node("bag_recorder")
    reliable = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)
    system = node.create_publisher(Int8, "/syropod_remote/system_state", 10)
    state = node.create_publisher(Int8, "/syropod_remote/robot_state", 10)
    velocity = node.create_publisher(Twist, "/syropod_remote/desired_velocity", 10)
    running: list[bool] = []
    count = [0]
    sent = [(0.0, 0.0, 0.0)]
    done: list[bool] = []
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connections = {topic: writer.add_connection(topic, msgtype, typestore=store)
                       for topic, msgtype in TOPICS.items()}

        def recorder(topic: str) -> Any:
            def write(raw: bytes, info: Any) -> None:
                # stamped when the middleware received it (as rosbag2 does), not when this loop got to it
                writer.write(connections[topic], int(info["received_timestamp"]), bytes(raw))
                if topic == "/desired_joint_states" and running and not done:
                    k = count[0]
                    count[0] += 1
                    if k >= len(schedule):
                        done.append(True)
                    elif schedule[k] != sent[0]:
                        twist = Twist()
                        twist.linear.x, twist.linear.y, twist.angular.z = schedule[k]
                        velocity.publish(twist)
                        sent[0] = schedule[k]
            return write

        for topic, msgtype in TOPICS.items():
            node.create_subscription(classes[msgtype], topic, recorder(topic), reliable, raw=True)
        def on_walkspace(message: Any) -> None:
            if not running:
                running.append(True)

        node.create_subscription(Float32MultiArray, "/shc/walkspace", on_walkspace, reliable)
        deadline = time.monotonic() + 120
        while node.count_publishers("/desired_joint_states") == 0 or system.get_subscription_count() == 0:
            if time.monotonic() > deadline:
                raise SystemExit("no shc ros2 node")
            rclpy.spin_once(node, timeout_sec=0.1)
        velocity.publish(Twist())
        last = 0.0
        deadline = time.monotonic() + len(schedule) / 100 * 3 + 120
        while not done and time.monotonic() < deadline:
            if time.monotonic() - last > 0.1:
                system.publish(Int8(data=1))
                state.publish(Int8(data=2))
                last = time.monotonic()
            rclpy.spin_once(node, timeout_sec=0.01)
        end = time.monotonic() + 0.5
        while time.monotonic() < end:
            rclpy.spin_once(node, timeout_sec=0.01)
    print("done" if done else "not done", count[0], flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
