"""``run-hw --on-fault adapt`` on the emulated bus (Bullet, 30 servos): an overload on BR_femur mid-walk fails the
leg, the other five walk on to the end, exit 5 (issue 39)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from shc_cli.hardware import protocol2 as p2
from shc_cli.spec.loading import load_robot
from tests.run_waits import wait_running
from tests.test_run_hw import SHC, _bus

pytestmark = pytest.mark.slow  # a real-time run of shc run-hw (a subprocess) on the emulated bus

GOAL_POSITION = 116
"""MX-106 (protocol 2) Goal Position address."""


def _goal_writes(bus: object, start: int) -> list[set[int]]:
    """The servo ids of each goal SYNC WRITE heard from packet ``start`` on."""
    writes = []
    for packet in bus.packets(start):  # type: ignore[attr-defined]
        if packet.instruction != p2.SYNC_WRITE or int.from_bytes(packet.params[0:2], "little") != GOAL_POSITION:
            continue
        length = int.from_bytes(packet.params[2:4], "little")
        body = packet.params[4:]
        writes.append({body[i] for i in range(0, len(body), length + 1)})
    return writes


def test_an_overloaded_femur_fails_its_leg_and_the_others_walk_on_to_the_end(tmp_path: Path) -> None:
    servos = load_robot("bullet").robot.hardware.servos
    femur = servos["BR_femur"].id
    leg = {s.id for key, s in servos.items() if key.startswith("BR_")}
    with _bus() as bus:
        process = subprocess.Popen([*SHC, "run-hw", "bullet", "--port", bus.port, "--out", str(tmp_path / "run"),
                                    "--velocity", "1,0,0", "--duration", "12", "--on-fault", "adapt"],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        wait_running(tmp_path / "run", process, extra_s=3.0)  # torque on, ~5 s start-up, 3 s walking
        marker = bus.fault(femur, "overload", True)  # the servo's next goal overloads it (torque off, alert bit)
        stdout, stderr = process.communicate(timeout=120)
        assert process.returncode == 5, stderr  # finished on fewer legs (docs/commands.md, exit codes)
        assert "FINISHED ON FEWER LEGS (failed: BR)" in stdout
        summary = json.loads((tmp_path / "run" / "summary.json").read_text())
        assert summary["failed_legs"] == ["BR"] and summary["fault"] is None
        assert summary["stopped_by_request"] is True and summary["final_state"] == "PACKED"
        writes = _goal_writes(bus, marker)
        with_femur = [i for i, ids in enumerate(writes) if femur in ids]
        assert len(with_femur) <= 2 and (not with_femur or with_femur[-1] <= 1)  # it overloads on the first
        assert all(not ids & leg for ids in writes[3:])  # then none of the leg's servos gets a goal
        assert len(writes) > 500 and all(len(ids) == 25 for ids in writes[3:])  # the other five legs to the end
        assert bus.table(servos["BR_tibia"].id, 64) == b"\0"  # all torque off at the end (--on-stop torque-off)
        events = [json.loads(line) for line in (tmp_path / "run" / "events.log").read_text().splitlines()]
        [failed] = [e for e in events if e["event"] == "leg_failed"]
        assert "BR_femur: overload" in failed["message"] and "leg BR failed" in failed["message"]
        walk = [e["message"] for e in events if e["event"] == "walk_state"]
        assert walk.count("walk state: STOPPED → STARTING") == 2  # walked, stopped for the re-plan, walked on


def _goals_of(bus: object, start: int, servo: int) -> list[int]:
    """The goal ticks written to ``servo`` by each goal SYNC WRITE from packet ``start`` on."""
    goals = []
    for packet in bus.packets(start):  # type: ignore[attr-defined]
        if packet.instruction != p2.SYNC_WRITE or int.from_bytes(packet.params[0:2], "little") != GOAL_POSITION:
            continue
        length = int.from_bytes(packet.params[2:4], "little")
        body = packet.params[4:]
        goals += [int.from_bytes(body[i + 1:i + 1 + length], "little", signed=True)
                  for i in range(0, len(body), length + 1) if body[i] == servo]
    return goals


def test_a_declared_failed_leg_is_held_retracted_while_the_others_walk(tmp_path: Path) -> None:
    """``run-hw --fail-leg BR``: the controller's re-planned walk on the servos; BR's goals settle on the
    retracted pose and stay there, the others keep moving; exit 0 (declared, not a fault)."""
    servos = load_robot("bullet").robot.hardware.servos
    with _bus() as bus:
        process = subprocess.Popen([*SHC, "run-hw", "bullet", "--port", bus.port, "--out", str(tmp_path / "run"),
                                    "--velocity", "1,0,0", "--duration", "4", "--fail-leg", "BR"],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        wait_running(tmp_path / "run", process, extra_s=1.0)
        marker = len(bus.packets())
        _, stderr = process.communicate(timeout=120)
        assert process.returncode == 0, stderr
        summary = json.loads((tmp_path / "run" / "summary.json").read_text())
        assert summary["gait"] == "planned" and summary["fault"] is None
        femur, walking = _goals_of(bus, marker, servos["BR_femur"].id), _goals_of(bus, marker, servos["AR_femur"].id)
        assert len(femur) > 200 and max(femur) - min(femur) == 0  # held once walking
        assert max(walking) - min(walking) > 50  # the others walk


def test_adapt_and_declared_failures_together_are_refused_in_one_line(tmp_path: Path) -> None:
    result = subprocess.run([*SHC, "run-hw", "bullet", "--port", "/dev/nonexistent", "--fail-leg", "BR",
                             "--on-fault", "adapt"], capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and result.stderr.count("\n") == 1 and "--on-fault" in result.stderr
