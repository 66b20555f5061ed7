"""A raw DDS reader (the ``cyclonedds`` package: another DDS vendor, no ROS at all) of ``shc ros2``'s
``/desired_joint_states`` as it is on the wire: topic ``rt/desired_joint_states``, type
``sensor_msgs::msg::dds_::JointState_`` (ROS 2's naming of the IDL type).

``python tests/ros2_dds_reader.py COUNT SECONDS OUT.json``: reads until COUNT samples came (at most SECONDS) and
writes the samples' joint names, the last positions and the count. ROS_DOMAIN_ID from the environment; loopback
only (no multicast leaves the machine).
"""

import json
import os
import sys
import time
from dataclasses import dataclass
from typing import Any, cast

from cyclonedds.core import Policy, Qos
from cyclonedds.domain import DomainParticipant
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.types import float64, int32, sequence, uint32
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic

LOOPBACK = ("<CycloneDDS><Domain><General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces>"
            "<AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex>"
            "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery></Domain></CycloneDDS>")


@dataclass
class Time_(IdlStruct, typename="builtin_interfaces::msg::dds_::Time_"):  # type: ignore[misc,call-arg,unused-ignore]
    sec: int32
    nanosec: uint32


@dataclass
class Header_(IdlStruct, typename="std_msgs::msg::dds_::Header_"):  # type: ignore[misc,call-arg,unused-ignore]
    stamp: Time_
    frame_id: str


@dataclass
class JointState_(IdlStruct, typename="sensor_msgs::msg::dds_::JointState_"):  # type: ignore[misc,call-arg,unused-ignore]
    header: Header_
    name: sequence[str]  # type: ignore[type-arg,unused-ignore]
    position: sequence[float64]  # type: ignore[type-arg,unused-ignore]
    velocity: sequence[float64]  # type: ignore[type-arg,unused-ignore]
    effort: sequence[float64]  # type: ignore[type-arg,unused-ignore]


def main() -> None:
    wanted, seconds, out = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3]
    os.environ["CYCLONEDDS_URI"] = LOOPBACK
    participant = DomainParticipant(int(os.environ["ROS_DOMAIN_ID"]))
    # ROS 2's representation is XCDR1 (offered beside XCDR2); types match by name and layout
    qos = Qos(Policy.Reliability.Reliable(0),
              Policy.DataRepresentation(use_cdrv0_representation=True, use_xcdrv2_representation=True),
              Policy.TypeConsistency.AllowTypeCoercion(ignore_sequence_bounds=True, ignore_string_bounds=True,
                                                       ignore_member_names=False, prevent_type_widening=False,
                                                       force_type_validation=False))
    reader = DataReader(participant, Topic(participant, "rt/desired_joint_states", JointState_), qos=qos)
    count, last = 0, None
    end = time.monotonic() + seconds
    while time.monotonic() < end and count < wanted:
        for sample in reader.take(N=100):
            if isinstance(sample, JointState_):
                count, last = count + 1, cast(Any, sample)
        time.sleep(0.01)
    with open(out, "w") as file:
        json.dump({"count": count, "names": list(last.name) if last else [],
                   "positions": list(last.position) if last else [],
                   "stamp": [last.header.stamp.sec, last.header.stamp.nanosec] if last else None}, file)


if __name__ == "__main__":
    main()
