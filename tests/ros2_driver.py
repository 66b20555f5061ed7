"""A ROS 2 driver node written with plain rclpy (not shc's node): the other side of ``shc ros2`` in the tests.

``python tests/ros2_driver.py SECONDS OUT.json``: waits for the node ``/shc``; lists, describes and gets its
parameters; sets ``swing_height`` out of its range (refused: the reason is kept) and, once the robot walks, inside
it; starts the remote's state machine (system_state OPERATIONAL, robot_state RUNNING, latched as a remote does) and
commands a walk; receives ``/desired_joint_states`` (reliable, its header stamps and receive times) and
``/shc/AR/state`` (OpenSHC's LegState, from its ``.msg`` definition: the type support generated from it); writes
what it saw to OUT.json. ROS_DOMAIN_ID and ROS_AUTOMATIC_DISCOVERY_RANGE come from the environment.
"""

from __future__ import annotations

import json
import sys
import time
from typing import Any


def main() -> None:
    seconds, out = float(sys.argv[1]), sys.argv[2]
    from shc_cli.ros2.interfaces import load

    load()  # OpenSHC's LegState: the type support generated from its .msg file
    import rclpy
    from geometry_msgs.msg import Twist
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import DescribeParameters, GetParameters, ListParameters, SetParameters
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Int8
    from syropod_highlevel_controller.msg import LegState

    rclpy.init()
    node = rclpy.create_node("ros2_driver")
    result: dict[str, Any] = {"stamps": [], "received": [], "leg_states": 0, "leg_names": []}

    def call(kind: Any, service: str, request: Any) -> Any:
        client: Any = node.create_client(kind, f"/shc/{service}")
        if not client.wait_for_service(timeout_sec=60.0):
            raise SystemExit(f"no /shc/{service}")
        future = client.call_async(request)
        rclpy.spin_until_future_complete(node, future, timeout_sec=10.0)
        return future.result()

    def set_swing(value: float) -> dict[str, Any]:
        parameter = Parameter(name="swing_height", value=ParameterValue(type=ParameterType.PARAMETER_DOUBLE,
                                                                         double_value=value))
        answer = call(SetParameters, "set_parameters", SetParameters.Request(parameters=[parameter])).results[0]
        return {"value": value, "successful": bool(answer.successful), "reason": str(answer.reason),
                "time": time.monotonic()}

    names: list[str] = []
    deadline = time.monotonic() + 60
    while "swing_height" not in names:  # the services come up with the node, its parameters once the robot is read
        if time.monotonic() > deadline:
            raise SystemExit(f"/shc declared no swing_height (parameters: {names})")
        time.sleep(0.2)
        names = list(call(ListParameters, "list_parameters", ListParameters.Request()).result.names)
    result["parameters"] = sorted(names)
    described = call(DescribeParameters, "describe_parameters", DescribeParameters.Request(names=["swing_height"]))
    descriptor = described.descriptors[0]
    low, high = descriptor.floating_point_range[0].from_value, descriptor.floating_point_range[0].to_value
    result["swing_range"] = [low, high]
    result["swing_description"] = descriptor.description
    wanted = ["swing_height", "step_frequency", "virtual_stiffness"]
    got = call(GetParameters, "get_parameters", GetParameters.Request(names=wanted))
    result.update({name: v.double_value for name, v in zip(wanted, got.values, strict=True)})
    result["out_of_range"] = set_swing(high + 0.05)

    reliable = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)

    def joints(message: JointState) -> None:
        result["stamps"].append(message.header.stamp.sec + message.header.stamp.nanosec * 1e-9)
        result["received"].append(time.time())

    def leg(message: LegState) -> None:
        result["leg_states"] += 1
        if message.name not in result["leg_names"]:
            result["leg_names"].append(message.name)

    node.create_subscription(JointState, "/desired_joint_states", joints, reliable)
    node.create_subscription(LegState, "/shc/AR/state", leg, reliable)
    system = node.create_publisher(Int8, "/syropod_remote/system_state", latched)
    state = node.create_publisher(Int8, "/syropod_remote/robot_state", latched)
    velocity = node.create_publisher(Twist, "/syropod_remote/desired_velocity", latched)
    system.publish(Int8(data=1))
    state.publish(Int8(data=2))
    walk = Twist()
    walk.linear.x = 0.5
    velocity.publish(walk)
    start = time.monotonic()
    inside = low + 0.75 * (high - low)
    sent = start
    while time.monotonic() - start < seconds:
        rclpy.spin_once(node, timeout_sec=0.02)
        if time.monotonic() - sent > 0.5:  # and at a rate, as syropod_remote (shc's subscriptions are volatile)
            sent = time.monotonic()
            system.publish(Int8(data=1))
            state.publish(Int8(data=2))
            velocity.publish(walk)
        if "in_range" not in result and time.monotonic() - start > seconds / 2:
            result["in_range"] = set_swing(inside)
            result["in_range"]["wall"] = time.time()
    infos = node.get_publishers_info_by_topic("/shc/AR/state")
    result["leg_state_hash"] = [str(i.topic_type_hash) for i in infos]
    result["leg_state_type"] = [i.topic_type for i in infos]
    result["joint_state_qos"] = [str(i.qos_profile.reliability) for i in
                                 node.get_publishers_info_by_topic("/desired_joint_states")]
    with open(out, "w") as file:
        json.dump(result, file)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
