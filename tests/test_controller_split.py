"""The controller is a façade over collaborators, one concern each (issue 35): no mixin, and no collaborator imports
the controller (they work on its shared state through :class:`shc_cli.control.core.ControllerCore`)."""

from __future__ import annotations

import ast

from shc_cli.control.controller import Command, Controller, RobotState
from shc_cli.spec.loading import load_gait, load_robot

from .conftest import ROOT

COLLABORATORS = ("transitions", "walking", "posing", "manipulation", "odometry_feed", "core", "robot_model")
"""The modules the controller is split into."""


def _imported(module: str) -> set[str]:
    tree = ast.parse((ROOT / "shc_cli" / "control" / f"{module}.py").read_text(encoding="utf-8"))
    names: set[str] = set()
    for node in ast.walk(tree):  # top-level, in functions and under TYPE_CHECKING alike
        if isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
        elif isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
    return names


def test_the_controller_is_no_mixin() -> None:
    assert Controller.__mro__ == (Controller, object)


def test_no_collaborator_imports_the_controller() -> None:
    importing = {module for module in COLLABORATORS if "shc_cli.control.controller" in _imported(module)}
    assert importing == set()


def test_the_collaborators_work_on_the_controllers_state() -> None:
    controller = Controller(load_robot("bullet").robot, load_gait("tripod").gait)
    parts = (controller.states, controller.walking, controller.posing, controller.manipulation, controller.feed)
    assert all(part.c is controller for part in parts)
    while controller.state != RobotState.RUNNING:
        controller.step(Command(state_request=RobotState.RUNNING))
    assert controller.walker is not None  # the state machine's start-up had the walking create the walker
    controller.step(Command(leg_toggle="AR"))
    assert controller.pending_toggle == 0 == controller.manipulation.pending_toggle
    assert controller.leg_modes is controller.manipulation.leg_modes
    assert controller.odometry is controller.feed.odometry
