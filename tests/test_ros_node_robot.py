"""``shc ros``'s robot and gaits without a ROS master: the parameter server's robot is read through a temporary
folder that is removed afterwards, and a bundled gait that does not load is left out with its reason logged — not
swallowed with every other error."""

from __future__ import annotations

import logging
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

import pytest
from ruamel.yaml import YAML

from shc_cli.domain.ros_node import SELECTABLE_GAITS, NodeConfig, _robot, selectable_gaits
from shc_cli.errors import Issue, SpecError
from shc_cli.spec import loading
from shc_cli.spec.loading import load_robot

from .conftest import ROOT

if TYPE_CHECKING:
    from shc_cli.ros.node import RosNode


class ParameterServer:
    """The two calls ``_robot`` makes of a node, over OpenSHC's parameter files as ``rosparam load`` loads them."""

    def __init__(self, *files: Path) -> None:
        self.tree: dict[str, object] = {}
        for file in files:
            loaded = YAML(typ="safe").load(file.read_text(encoding="utf-8"))
            for key, value in loaded.items():
                existing = self.tree.setdefault(key, {})
                assert isinstance(existing, dict) and isinstance(value, dict)
                existing.update(value)

    def get_param(self, key: str) -> object:
        node: object = self.tree
        for part in key.strip("/").split("/"):
            assert isinstance(node, dict)
            node = node[part]
        return node

    def has_param(self, key: str) -> bool:
        try:
            self.get_param(key)
        except KeyError:
            return False
        return True


def test_the_servers_robot_is_read_and_its_temporary_folder_removed(tmp_path: Path,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))
    server = ParameterServer(ROOT / "golden" / "openshc" / "bullet_insectoid.yaml",
                             ROOT / "golden" / "openshc" / "gait.yaml")
    node: RosNode = server  # type: ignore[assignment]  # the two calls of a node _robot makes
    robot, gait, _, gaits = _robot(node, NodeConfig(robot="server"), tmp_path / "run")
    assert robot.name == "bullet" and len(robot.legs) == 6 and gait.name == "tripod"
    assert set(gaits) == set(SELECTABLE_GAITS)  # a hexapod walks every bundled gait
    assert list(temporary.iterdir()) == []  # the shc files written from the server are gone


def test_a_gait_that_does_not_load_is_left_out_with_its_reason(monkeypatch: pytest.MonkeyPatch,
                                                               caplog: pytest.LogCaptureFixture) -> None:
    real = loading.load_gait

    def broken_amble(name: str | Path, relative_to: Path | None = None) -> loading.LoadedGait:
        if name == "amble":
            raise SpecError([Issue(None, None, "duty_factor", "must be below 1", "fix the gait file")])
        return real(name, relative_to)

    monkeypatch.setattr(loading, "load_gait", broken_amble)
    robot = load_robot("bullet").robot
    with caplog.at_level(logging.WARNING, logger="shc_cli.domain.ros_node"):
        gaits = selectable_gaits(robot)
    assert set(gaits) == {"wave", "ripple", "tripod"}
    (message,) = [r.getMessage() for r in caplog.records if "amble" in r.getMessage()]
    assert message.startswith("gait amble is not offered to gait_selection: ") and "must be below 1" in message


def test_a_bug_while_loading_a_gait_is_not_swallowed(monkeypatch: pytest.MonkeyPatch) -> None:
    def failing(name: str | Path, relative_to: Path | None = None) -> loading.LoadedGait:
        raise RuntimeError("a bug")

    monkeypatch.setattr(loading, "load_gait", failing)
    with pytest.raises(RuntimeError, match="a bug"):
        selectable_gaits(load_robot("bullet").robot)
