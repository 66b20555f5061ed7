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
