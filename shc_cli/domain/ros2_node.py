"""``shc ros2``: OpenSHC's node on ROS 2 — ``shc ros``'s session (:mod:`shc_cli.domain.ros_node`) with a ROS 2 node
as its transport (:mod:`shc_cli.ros2.node`): the same controller, loop, remote and outputs, ROS 2's types, QoS and
parameters."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from shc_cli.domain.result import RunResult

if TYPE_CHECKING:
    from shc_cli.domain.ros_node import NodeConfig
    from shc_cli.ros.transport import Node


def run_node2(config: NodeConfig, params_file: Path | None = None,
              on_ready: Callable[[str], None] | None = None) -> RunResult:
    """Run the ROS 2 node until its duration passes or a signal; the finished run directory.

    Raises:
        ShcError: bad input, the ``ros2`` extra missing, a parameter file that does not read (one line).
    """
    from shc_cli.domain.ros_config import SERVER
    from shc_cli.domain.ros_node import run_node
    from shc_cli.errors import Issue, SpecError

    if config.robot == SERVER:  # refused before the node joins the network
        raise SpecError([Issue(None, None, "robot", "'server' reads ROS 1's parameter server",
                               "give a robot file (shc import openshc converts OpenSHC's parameters)")])
    if params_file is not None and not params_file.is_file():
        raise SpecError([Issue(params_file, None, "--params-file", "no such file",
                               "give a ROS 2 parameter file (shc: ros__parameters: ...)")])
    if params_file is not None:
        _check_ranges(config, _check_params_file(params_file))

    def open_node(c: NodeConfig) -> Node:
        from shc_cli.ros2.node import Ros2Node

        return Ros2Node(c.name, params_file)

    return run_node(config, on_ready, open_node)


def _check_params_file(path: Path) -> dict[str, object]:
    """A ROS 2 parameter file: ``NODE: ros__parameters: {name: value}`` (rcl's parser would abort the process on
    worse, so it is read here first)."""
    from ruamel.yaml import YAML
    from ruamel.yaml.error import YAMLError

    from shc_cli.errors import Issue, SpecError

    try:
        tree = YAML(typ="safe").load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, YAMLError) as error:
        raise SpecError([Issue(path, None, "--params-file", f"does not read as YAML ({error})".splitlines()[0],
                               "write NODE: ros__parameters: {name: value}")]) from None
    if not isinstance(tree, dict) or not all(isinstance(v, dict) and isinstance(v.get("ros__parameters"), dict)
                                             for v in tree.values()):
        raise SpecError([Issue(path, None, "--params-file", "not a ROS 2 parameter file",
                               "write NODE: ros__parameters: {name: value} (NODE: the node's name, or /**)")])
    values: dict[str, object] = {}
    for parameters in tree.values():
        values.update(parameters["ros__parameters"])
    return values


def _check_ranges(config: NodeConfig, values: dict[str, object]) -> None:
    """A dynamic parameter's start value outside the robot's range refuses the start before anything is written
    (the node would refuse it too, with the run directory begun)."""
    from shc_cli.errors import Issue, SpecError
    from shc_cli.ros2.parameters import adjustable
    from shc_cli.spec.loading import load_robot

    ranges = adjustable(load_robot(config.robot).robot)
    for name, value in values.items():
        if name in ranges:
            _, low, high = ranges[name]
            if not isinstance(value, int | float) or isinstance(value, bool) or not low <= value <= high:
                raise SpecError([Issue(None, None, f"--params-file: {name}", f"outside its range [{low:g}, "
                                       f"{high:g}]", "give a value in the robot's range")])
