"""A syropod_remote stand-in written with Debian's rospy (not shc's node): replays the insectoid recording's input
schedule (golden/openshc-runs/insectoid_events.csv) on OpenSHC's remote topics, shortened by a factor.

Run with Debian's interpreter: ``/usr/bin/python3 tests/ros_remote_driver.py SCALE`` (ROS_MASTER_URI set). As the
recording's driver did, it publishes system_state OPERATIONAL and robot_state RUNNING once (latched), waits for
the node's first /shc/walkspace message (RUNNING), then publishes each segment's desired_velocity once when the
segment starts, and counts the segment's length in the node's cycles (its /desired_joint_states). Each new
velocity goes out from the callback of a /desired_joint_states message, so it reaches the node and any recorder
between the same two cycles; a free-running publisher can land within a millisecond of a cycle's output, where
two subscribers may see it on different sides of it.
"""

import sys
import threading

import rospy
from geometry_msgs.msg import Twist
from sensor_msgs.msg import JointState
from std_msgs.msg import Float32MultiArray, Int8

SEGMENTS = [(0.5, 0.0, 0.0, 20.0), (1.0, 0.0, 0.0, 20.0), (0.0, 0.0, 0.0, 5.0), (0.0, 0.0, 0.5, 20.0),
            (0.0, 0.0, 0.0, 5.0)]
"""The recording's segments: vx, vy, wz (throttle fractions), duration [s]."""


def main() -> None:
    scale = float(sys.argv[1]) if len(sys.argv) > 1 else 1.0
    rospy.init_node("syropod_remote_stand_in", disable_signals=True)
    system = rospy.Publisher("/syropod_remote/system_state", Int8, queue_size=1, latch=True)
    state = rospy.Publisher("/syropod_remote/robot_state", Int8, queue_size=1, latch=True)
    velocity = rospy.Publisher("/syropod_remote/desired_velocity", Twist, queue_size=10, latch=True)
    running = threading.Event()
    done = threading.Event()
    schedule = []
    for vx, vy, wz, seconds in SEGMENTS:
        schedule += [(vx, vy, wz)] * max(1, round(seconds * scale * 100))
    start: list[int] = []
    sent: list[tuple[float, float, float]] = [(0.0, 0.0, 0.0)]

    def on_joints(message: JointState) -> None:
        """Publish the velocity of the node's current cycle when it changes (cycles counted by header.seq, so a
        skipped message — queue size 1 keeps the newest — does not stretch the schedule)."""
        if not running.is_set() or done.is_set():
            return
        if not start:
            start.append(message.header.seq)
        k = message.header.seq - start[0]
        if k >= len(schedule):
            done.set()
            return
        if schedule[k] != sent[0]:
            twist = Twist()
            twist.linear.x, twist.linear.y, twist.angular.z = schedule[k]
            velocity.publish(twist)
            sent[0] = schedule[k]

    rospy.Subscriber("/shc/walkspace", Float32MultiArray, lambda m: running.set())
    rospy.Subscriber("/desired_joint_states", JointState, on_joints, queue_size=1, tcp_nodelay=True)
    rospy.sleep(1.0)
    velocity.publish(Twist())
    system.publish(Int8(1))
    state.publish(Int8(2))
    print("running" if running.wait(120) else "never RUNNING", flush=True)
    print("done" if done.wait(len(schedule) / 100 * 3 + 30) else "not done", flush=True)


if __name__ == "__main__":
    main()
