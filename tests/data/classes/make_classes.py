"""Writes the small descriptions of tests/data/classes (one property of issue 37 each); run from the repo root:
``python tests/data/classes/make_classes.py``. Written for these tests (no third-party source)."""

from __future__ import annotations

import math
from pathlib import Path

HERE = Path(__file__).parent
HIPS = [("fr", 0.12, -0.08), ("mr", 0.0, -0.1), ("rr", -0.12, -0.08),
        ("rl", -0.12, 0.08), ("ml", 0.0, 0.1), ("fl", 0.12, 0.08)]
INERTIA = '<inertia ixx="2e-5" ixy="0" ixz="0" iyy="2e-5" iyz="0" izz="2e-5"/>'


def link(name: str, mass: float, extra: str = "") -> str:
    return (f'  <link name="{name}"><inertial><origin xyz="0 0 0"/><mass value="{mass}"/>{INERTIA}</inertial>'
            f"{extra}</link>")


def joint(name: str, kind: str, parent: str, child: str, xyz: str, rpy: str = "0 0 0", axis: str = "0 0 1",
          limits: str = 'lower="-1.6" upper="1.6"') -> str:
    body = f'<parent link="{parent}"/><child link="{child}"/><origin xyz="{xyz}" rpy="{rpy}"/>'
    if kind != "fixed":
        body += f'<axis xyz="{axis}"/><limit {limits} effort="1.5" velocity="6.0"/>'
    return f'  <joint name="{name}" type="{kind}">{body}</joint>'


def body(name: str = "base_link", mass: float = 1.5) -> str:
    return link(name, mass, '<collision><geometry><box size="0.3 0.2 0.05"/></geometry></collision>')


SPHERE = '<collision><geometry><sphere radius="0.01"/></geometry></collision>'
TIBIA_ROD = ('<collision><origin xyz="0.06 0 0" rpy="0 1.5707963267948966 0"/><geometry>'
             '<cylinder radius="0.01" length="0.12"/></geometry></collision>')


def hexapod(kind: str = "revolute", limits: str = 'lower="-1.6" upper="1.6"', femur_rpy: str = "0 0 0",
            femur_axis: str = "0 1 0", tibia_rpy: str = "0 0 0", tibia_axis: str = "0 1 0", foot: bool = True,
            base: str = "base_link", tibia_extra: str = "", foot_xyz: str = "0.12 0 0",
            narrow: tuple[str, str, str] | None = None, tibia_at: str = "0.08 0 0") -> list[str]:
    """Six 3-joint legs (coxa yaw, femur and tibia pitch), flat at the zero pose; a foot link with a sphere at
    the tibia's end unless ``foot`` is False."""
    lines = []
    coxa_limits, femur_limits, tibia_limits = narrow or (limits, limits, limits)
    for leg, x, y in HIPS:
        yaw = math.atan2(y, x)
        lines += [link(f"{leg}_coxa", 0.05), link(f"{leg}_femur", 0.08), link(f"{leg}_tibia", 0.06, tibia_extra),
                  joint(f"{leg}_coxa_joint", kind, base, f"{leg}_coxa", f"{x} {y} 0", f"0 0 {yaw!r}",
                        limits=coxa_limits),
                  joint(f"{leg}_femur_joint", kind, f"{leg}_coxa", f"{leg}_femur", "0.04 0 0", femur_rpy,
                        femur_axis, femur_limits),
                  joint(f"{leg}_tibia_joint", kind, f"{leg}_femur", f"{leg}_tibia", tibia_at, tibia_rpy,
                        tibia_axis, tibia_limits)]
        if foot:
            lines += [link(f"{leg}_foot", 0.01, SPHERE),
                      joint(f"{leg}_foot_joint", "fixed", f"{leg}_tibia", f"{leg}_foot", foot_xyz)]
    return lines


def robot(name: str, lines: list[str], head: str = "") -> str:
    return f'<?xml version="1.0"?>\n<robot name="{name}"{head}>\n' + "\n".join(lines) + "\n</robot>\n"


def mjcf_hexapod() -> str:
    """11: the same hexapod as MJCF: a free trunk, the coxa body holding both the yaw and the femur joint (two
    hinges in one body, the second 0.04 m out), euler and axis-angle frames, a knee ``ref`` of 0.3 rad, foot spheres
    on the tibia bodies, position-free motors with ctrlrange and gear."""
    legs = []
    motors = []
    for leg, x, y in HIPS:
        yaw = math.atan2(y, x)
        legs.append(f"""    <body name="{leg}_coxa" pos="{x} {y} 0" euler="0 0 {yaw!r}">
      <inertial pos="0.02 0 0" mass="0.13" diaginertia="2e-5 2e-5 2e-5"/>
      <joint name="{leg}_coxa_joint" axis="0 0 1" range="-1.6 1.6"/>
      <joint name="{leg}_femur_joint" pos="0.04 0 0" axis="0 1 0" range="-1.6 1.6"/>
      <geom type="capsule" fromto="0.04 0 0 0.12 0 0" size="0.008" contype="0" conaffinity="0"/>
      <body name="{leg}_tibia" pos="0.12 0 0" axisangle="0 1 0 0.3">
        <inertial pos="0.06 0 0" mass="0.07" diaginertia="2e-5 2e-5 2e-5"/>
        <joint name="{leg}_tibia_joint" axis="0 1 0" range="-1.3 1.9" ref="0.3"/>
        <geom name="{leg}_foot" type="sphere" pos="0.12 0 0" size="0.01"/>
      </body>
    </body>""")
        motors += [f'    <motor joint="{leg}_{part}_joint" ctrlrange="-1 1" gear="1.5"/>'
                   for part in ("coxa", "femur", "tibia")]
    return ("<mujoco model=\"mjcf_hexapod\">\n  <compiler angle=\"radian\"/>\n  <worldbody>\n"
            '    <geom name="floor" type="plane" size="2 2 0.1"/>\n'
            '    <body name="trunk" pos="0 0 0.3">\n    <freejoint/>\n'
            '    <geom type="box" size="0.15 0.1 0.025" mass="1.5"/>\n'
            + "\n".join(legs) + "\n    </body>\n  </worldbody>\n  <actuator>\n" + "\n".join(motors)
            + "\n  </actuator>\n</mujoco>\n")


def mjcf_quadruped() -> str:
    """11: a quadruped in the style of MuJoCo Menagerie's (written here, not copied): default classes with a
    childclass, legs straight down at qpos0, the knee limited to a bent range, foot sphere geoms of a class on the
    calf bodies, visual geoms that do not collide, position actuators with a forcerange."""
    legs, motors = [], []
    for leg, x, y in [("FR", 0.19, -0.047), ("FL", 0.19, 0.047), ("RR", -0.19, -0.047), ("RL", -0.19, 0.047)]:
        side = -1.0 if y < 0 else 1.0
        legs.append(f"""      <body name="{leg}_hip" pos="{x} {y} 0">
        <inertial pos="0 {0.01 * side} 0" mass="0.68" diaginertia="4e-4 5e-4 4e-4"/>
        <joint name="{leg}_hip_joint" class="abduction"/>
        <geom class="visual" type="cylinder" size="0.045 0.02" quat="1 1 0 0"/>
        <body name="{leg}_thigh" pos="0 {0.08 * side} 0">
          <inertial pos="0 0 -0.03" mass="1.0" diaginertia="5e-3 5e-3 1e-3"/>
          <joint name="{leg}_thigh_joint" class="hip"/>
          <geom class="visual" type="box" size="0.015 0.012 0.1" pos="0 0 -0.1"/>
          <body name="{leg}_calf" pos="0 0 -0.213">
            <inertial pos="0 0 -0.1" mass="0.2" diaginertia="1e-3 1e-3 3e-5"/>
            <joint name="{leg}_calf_joint" class="knee"/>
            <geom class="visual" type="capsule" fromto="0 0 0 0 0 -0.2" size="0.01"/>
            <geom name="{leg}_foot" class="foot" pos="0 0 -0.213"/>
          </body>
        </body>
      </body>""")
        motors += [f'    <position class="{kind}" name="{leg}_{part}" joint="{leg}_{part}_joint"/>'
                   for part, kind in (("hip", "abduction"), ("thigh", "hip"), ("calf", "knee"))]
    return f"""<mujoco model="mjcf_quadruped">
  <compiler angle="radian"/>
  <default>
    <default class="dog">
      <joint axis="0 1 0" damping="0.5"/>
      <position kp="100" forcerange="-23.7 23.7"/>
      <default class="abduction"><joint axis="1 0 0" range="-0.86 0.86"/><position ctrlrange="-0.86 0.86"/></default>
      <default class="hip"><joint range="-0.69 4.5"/><position ctrlrange="-0.69 4.5"/></default>
      <default class="knee"><joint range="-2.82 -0.89"/><position forcerange="-35.55 35.55" ctrlrange="-2.82 -0.89"/>
      </default>
      <default class="visual"><geom contype="0" conaffinity="0" group="2"/></default>
      <default class="foot"><geom type="sphere" size="0.023" friction="0.8 0.02 0.01"/></default>
    </default>
  </default>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <body name="trunk" pos="0 0 0.45" childclass="dog">
      <freejoint/>
      <inertial pos="0.02 0 0" mass="5.2" diaginertia="0.015 0.05 0.055"/>
      <geom type="box" size="0.19 0.05 0.055"/>
{chr(10).join(legs)}
    </body>
  </worldbody>
  <actuator>
{chr(10).join(motors)}
  </actuator>
</mujoco>
"""


def main() -> None:
    files = {
        # 1: a vendor macro's continuous joints (no lower/upper anywhere).
        "continuous_hexapod.urdf": robot("continuous_hexapod", [body(), *hexapod("continuous", limits="")]),
        # 3: pi/2 written 1.57 and pi 3.14: the femur frame turned 1.57 about x (its axis z), the tibia's 3.14
        # about y (its axis -z): the knee axis 0.0016 rad from the femur's, tilted along the femur.
        "rounded_rpy_hexapod.urdf": robot("rounded_rpy_hexapod", [body(), *hexapod(
            femur_rpy="1.57 0 0", femur_axis="0 0 1", tibia_rpy="0 3.14 0", tibia_axis="0 0 -1",
            foot_xyz="-0.12 0 0")]),
        # 6: no foot link, the tibia frame on the knee axis, a rod along the tibia as its collision geometry.
        "rod_tibia_hexapod.urdf": robot("rod_tibia_hexapod", [body(), *hexapod(foot=False, tibia_extra=TIBIA_ROD)]),
        # 4: a massless spawn frame as the root, the body fixed to it 1.2 m away and 0.4 m up.
        "spawn_root_hexapod.urdf": robot("spawn_root_hexapod", [
            '  <link name="spawn"/>', body("torso"),
            joint("spawn_to_torso", "fixed", "spawn", "torso", "1.0 0.6 0.4", "0 0 0.3"),
            *hexapod(base="torso")]),
    }
    # 7: a hobby hexapod's narrow limits: the coxa ±0.6 rad, the femur 0.2-0.9 rad down, the knee 0.8-1.5 bent.
    files["narrow_limits_hexapod.urdf"] = robot("narrow_limits_hexapod", [body(), *hexapod(narrow=(
        'lower="-0.6" upper="0.6"', 'lower="0.2" upper="0.9"', 'lower="0.8" upper="1.5"'))])
    # 9: standing at the zero pose with the knees below the feet (femur 1.2 rad down, tibia 0.6 rad up).
    files["low_knees_hexapod.urdf"] = robot("low_knees_hexapod", [body(), *hexapod(
        femur_rpy="0 1.2 0", tibia_rpy="0 -1.8 0", tibia_at="0.14 0 0", foot_xyz="0.08 0 0")])
    # 2: a CAD exporter: the body and the feet are children of the root through floating joints.
    detached = [link("root", 0.0), body("chassis"), joint("root_chassis", "floating", "root", "chassis", "0 0 0")]
    detached += [line for line in hexapod(base="chassis", foot=False)]
    for leg, x, y in HIPS:
        reach = 0.04 + 0.08 + 0.12
        norm = math.hypot(x, y)
        fx, fy = x + reach * x / norm, y + reach * y / norm
        detached += [link(f"{leg}_foot", 0.01, SPHERE),
                     joint(f"{leg}_foot_float", "floating", "root", f"{leg}_foot", f"{fx!r} {fy!r} 0")]
    files["detached_feet_hexapod.urdf"] = robot("detached_feet_hexapod", detached)
    # 5: a ros2_control block naming its parameter file in a package that is not installed here.
    control = ['  <ros2_control name="hexapod_system" type="system">',
               '    <hardware><plugin>mock_components/GenericSystem</plugin>',
               '      <param name="calibration">$(find my_hexapod_control)/config/calibration.yaml</param></hardware>',
               *(f'    <joint name="{leg}_{part}_joint"><command_interface name="position"/></joint>'
                 for leg, _, _ in HIPS for part in ("coxa", "femur", "tibia")),
               "  </ros2_control>",
               '  <gazebo><plugin filename="libgz_ros2_control-system.so"'
               ' name="gz_ros2_control::GazeboSimROS2ControlPlugin">',
               "    <parameters>$(find my_hexapod_control)/config/controllers.yaml</parameters></plugin></gazebo>"]
    files["ros2_control_hexapod.urdf.xacro"] = robot("ros2_control_hexapod", [body(), *hexapod(), *control],
                                                     ' xmlns:xacro="http://www.ros.org/wiki/xacro"')
    files["mjcf_hexapod.xml"] = mjcf_hexapod()
    files["mjcf_quadruped.xml"] = mjcf_quadruped()
    for name, text in files.items():
        (HERE / name).write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
