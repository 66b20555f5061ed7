"""``shc hw scan|check|jog|emulate`` end to end against emulated buses served by processes of their own
(shc_cli/hardware/emulator_process.py): what each finds, reads and writes on the bus, and what jog writes back to the
robot file (only the confirmed fields; the file never half-written). Exit codes: 1 check found a joint outside its
limits, 2 bad input (one line), 3 a servo fault (named, torque off)."""

from __future__ import annotations

import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from shc_cli.domain.bringup.servo_file import edit_servos
from shc_cli.errors import SpecError
from shc_cli.hardware import protocol1 as p1
from shc_cli.hardware.emulator_process import EmulatorProcess, Heard

from .test_cli import run

SHC = [sys.executable, "-m", "shc_cli.cli"]
JOINTS = [f"{leg}_{joint}" for leg in ("AR", "BR", "CR", "CL", "BL", "AL") for joint in ("coxa", "femur", "tibia")]


Shc = Callable[..., subprocess.CompletedProcess[str]]


@pytest.fixture
def shc(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> Shc:
    """``shc`` in the test's process (tests/test_cli.py's ``run``): the same exit code, stdout and stderr, without an
    interpreter's start-up and imports per call; the buses are emulated by processes of their own."""
    def call(*args: str) -> subprocess.CompletedProcess[str]:
        code, out, err = run(list(args), capsys, monkeypatch)
        return subprocess.CompletedProcess(["shc", *args], code, out, err)
    return call


def _robot(folder: Path, model: str = "AX-12A") -> Path:
    """A hexapod (openshc_default) on one bus of ``model`` servos, ids 1–18; AL_coxa mapped against its joint."""
    lines = ['extends = "openshc_default"', 'name = "bringup_hexapod"', "time_delta = 0.04",
             "# a comment the jog keeps", "[hardware]", f'model = "{model}"', "", "[hardware.servos]"]
    lines += [f"{key} = {{ id = {k + 1} }}" if key != "AL_coxa" else f"{key} = {{ id = {k + 1}, direction = -1 }}  "
              "# turned" for k, key in enumerate(JOINTS)]
    path = folder / "hexapod.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


TIBIA_TICKS = 512 - 223
"""The tibias' servos stand at −1.14 rad (openshc_default's unpacked angle; its tibia limits exclude 0)."""


def _bus(model: str = "AX-12A", skip: int | None = None) -> EmulatorProcess:
    return EmulatorProcess({k + 1: model for k in range(18) if k + 1 != skip},
                           positions={k + 1: TIBIA_TICKS for k in range(2, 18, 3)})


def test_scan_finds_each_family_at_its_baud_and_only_there(shc: Shc) -> None:
    with EmulatorProcess({1: "AX-12A", 7: "AX-12A"}, baud=1_000_000, check_baud=True) as ax, \
            EmulatorProcess({3: "STS3215"}, baud=57_600, check_baud=True) as sts, \
            EmulatorProcess({5: "XM430-W350"}, baud=57_600) as xm:
        result = shc("hw", "scan", "--port", ax.port, "--port", sts.port, "--port", xm.port, "--ids", "0-8",
                     "--timeout-ms", "30")
    assert result.returncode == 0, result.stderr
    rows = [line.split() for line in result.stdout.splitlines()[1:-1]]
    assert rows == [[ax.port, "1000000", "1.0", "1", "AX-12A", "24"], [ax.port, "1000000", "1.0", "7", "AX-12A", "24"],
                    [sts.port, "57600", "feetech", "3", "STS3215", "3.10"],
                    [xm.port, "57600", "2.0", "5", "XM430-W350", "45"]], result.stdout
    assert result.stdout.splitlines()[-1] == "4 servos found"


def _heard(bus: EmulatorProcess, expected: int, within_s: float = 30.0) -> list[Heard]:
    """The packets ``bus`` heard, once it has parsed at least ``expected`` (a loaded machine may leave the emulator
    process behind the scan that wrote them) or ``within_s`` has passed."""
    deadline = time.monotonic() + within_s
    heard = bus.packets()
    while len(heard) < expected and time.monotonic() < deadline:
        time.sleep(0.05)
        heard = bus.packets()
    return heard


def test_scan_of_an_empty_bus_is_quick(shc: Shc) -> None:
    """Protocol 2.0: one broadcast ping per baud (not a timeout per id); Protocol 1.0: one ping per id asked for.
    Counted on the bus, not timed: a wall-clock bound (8 s) failed on a loaded machine (issue 42 point 15)."""
    with EmulatorProcess({}, baud=1_000_000, check_baud=True) as empty:
        began = time.monotonic()
        result = shc("hw", "scan", "--port", empty.port, "--protocol", "2.0", "--baud", "1000000")
        broadcast = time.monotonic() - began
        heard = _heard(empty, 1)
    assert result.returncode == 0 and result.stdout.strip() == "no servo answered", result.stderr
    assert [(p.servo, p.instruction) for p in heard] == [(p1.BROADCAST, p1.PING)]  # one packet for 253 ids
    with EmulatorProcess({200: "AX-12A"}, baud=1_000_000, check_baud=True) as quiet:  # nobody in 1-30
        began = time.monotonic()
        pings = shc("hw", "scan", "--port", quiet.port, "--protocol", "1.0", "--baud", "1000000", "--ids", "1-30")
        unicast = time.monotonic() - began
        heard = _heard(quiet, 30)
    assert pings.returncode == 0 and pings.stdout.strip() == "no servo answered", pings.stderr
    assert [(p.servo, p.instruction) for p in heard] == [(i, p1.PING) for i in range(1, 31)]  # once each, no retry
    print(f"empty bus: Protocol 2.0 broadcast {broadcast:.2f} s, 30 Protocol 1.0 pings {unicast:.2f} s")


@pytest.mark.parametrize(("args", "message"), [
    (["--ids", "5-300"], "--ids: '5-300' is not an id range (give FIRST-LAST within 0-252, e.g. 1-18)"),
    (["--protocol", "3.0"], "--protocol: '3.0' is not a protocol (give 2.0, 1.0, feetech)"),
    (["--port", "/dev/ttyNOTHERE0"], "/dev/ttyNOTHERE0: cannot open the serial port: no such device"),
])
def test_scan_bad_input_is_one_line_exit_2(args: list[str], message: str, shc: Shc) -> None:
    result = shc("hw", "scan", *(["--port", "/dev/ttyNOTHERE0"] if "--port" not in args else []), *args)
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], result.stderr


def test_check_reads_without_moving_and_names_a_joint_outside_its_limits(tmp_path: Path, shc: Shc) -> None:
    robot = _robot(tmp_path)
    with _bus() as bus:
        result = shc("hw", "check", str(robot), "--port", bus.port)
        assert result.returncode == 0, result.stderr
        assert "every joint within its limits" in result.stdout
        bus.set(3, 36, 800)  # AR_tibia's servo turned far off (present position 800: +1.47 rad, its max −0.1)
        outside = shc("hw", "check", str(robot), "--port", bus.port)
        writes = [p for p in bus.packets() if p[1] in (p1.WRITE, p1.SYNC_WRITE, p1.REG_WRITE)]
    assert outside.returncode == 1, outside.stderr
    row = next(line for line in outside.stdout.splitlines() if line.startswith("AR_tibia"))
    assert "800" in row.split() and "OUTSIDE by" in row
    assert "1 joint outside the limits: AR_tibia" in outside.stderr
    assert writes == []  # no goal, no torque, no setting written


def test_check_refuses_a_missing_servo_and_faults_on_a_hot_one(tmp_path: Path, shc: Shc) -> None:
    robot = _robot(tmp_path)
    with _bus(skip=8) as bus:
        missing = shc("hw", "check", str(robot), "--port", bus.port)
    assert missing.returncode == 2 and "CR_femur: servo 8 does not answer" in missing.stderr, missing.stderr
    assert len(missing.stderr.strip().splitlines()) == 1
    with _bus() as bus:
        bus.fault(8, "error_bits", 4)  # overheating
        hot = shc("hw", "check", str(robot), "--port", bus.port)
    assert hot.returncode == 3 and "CR_femur: hardware error (overheating)" in hot.stderr, hot.stderr


def test_jog_moves_one_joint_torque_limited_and_back_and_writes_the_answers(tmp_path: Path, shc: Shc) -> None:
    robot = _robot(tmp_path)
    before = robot.read_text()
    with _bus() as bus:
        result = shc("hw", "jog", str(robot), "--port", bus.port, "--joint", "AR_coxa", "--joint", "AL_coxa",
                     "--answers", "n,k,y,h", "--angle", "0.1", "--torque", "0.25")
        packets = bus.packets()
        torque_on = [bus.torque_on(k + 1) for k in range(18)]
    assert result.returncode == 0, result.stderr
    # AR_coxa (id 1): torque limit 25 % (256 of 1023) written before the torque goes on, goal 512 + 0.1 rad in AX
    # ticks (1024 per 300°: 19.56 per 0.1 rad) and back, torque off, the limit restored (1023)
    writes = [(p[2][0], int.from_bytes(p[2][1:], "little")) for p in packets if p[0] == 1 and p[1] == p1.WRITE]
    assert writes == [(34, 256), (30, 512), (24, 1), (30, 532), (30, 512), (24, 0), (34, 1023)], writes
    al = [(p[2][0], int.from_bytes(p[2][1:], "little")) for p in packets if p[0] == 16 and p[1] == p1.WRITE]
    assert (30, 512 - 20) in al  # AL_coxa is mapped against its joint: +0.1 rad is 20 ticks down
    assert not any(torque_on)
    after = robot.read_text()
    changed = [(a, b) for a, b in zip(before.splitlines(), after.splitlines(), strict=True) if a != b]
    assert changed == [("AR_coxa = { id = 1 }", "AR_coxa = { id = 1, direction = -1 }"),
                       ("AL_coxa = { id = 16, direction = -1 }  # turned",
                        "AL_coxa = { id = 16, direction = -1, zero_ticks = "
                        + after.split("AL_coxa = { id = 16, direction = -1, zero_ticks = ")[1].split()[0]
                        + " }  # turned")]
    zero = int(after.split("zero_ticks = ")[1].split()[0])
    assert abs(zero - 512) <= 3  # where the servo came back to
    assert "AR_coxa: direction = -1" in result.stdout


def test_jog_writes_nothing_after_a_bad_answer_or_a_fault(tmp_path: Path, shc: Shc) -> None:
    robot = _robot(tmp_path)
    before = robot.read_text()
    with _bus() as bus:
        bad = shc("hw", "jog", str(robot), "--port", bus.port, "--joint", "AR_coxa", "--joint", "AR_femur",
                  "--answers", "n,k,x")
        bus.fault(2, "overload_at_goal", True)
        fault = shc("hw", "jog", str(robot), "--port", bus.port, "--joint", "AR_coxa", "--joint", "AR_femur",
                    "--answers", "n,k,y,k")
        torque_on = [bus.torque_on(k + 1) for k in range(18)]
    assert bad.returncode == 2 and "'x' answers none of AR_femur's choices (y/n/s); nothing written" in bad.stderr
    assert [line for line in bad.stderr.splitlines() if not line.endswith("and back")] == [
        "error: --answers: 'x' answers none of AR_femur's choices (y/n/s); nothing written (run jog again)"]
    assert fault.returncode == 3 and "fault: AR_femur (servo 2): overload" in fault.stderr, fault.stderr
    assert not any(torque_on)
    assert robot.read_text() == before
    unasked = shc("hw", "jog", "openshc_default", "--port", "/dev/null")
    assert unasked.returncode == 2 and "not a robot file (jog writes the servo map back)" in unasked.stderr


def test_servo_file_edits_sub_tables_and_refuses_inherited_entries(tmp_path: Path) -> None:
    path = tmp_path / "r.toml"
    path.write_text('[hardware.servos.AR_coxa]\nid = 11  # front\n\n[hardware.servos.AR_femur]\nid = 12\n'
                    'direction = 1\n[walker]\nx = 1\n')
    text = edit_servos(path, {"AR_femur": {"direction": -1, "zero_ticks": 2000}, "AR_coxa": {"zero_ticks": 7}})
    assert text == ('[hardware.servos.AR_coxa]\nzero_ticks = 7\nid = 11  # front\n\n[hardware.servos.AR_femur]\n'
                    'zero_ticks = 2000\nid = 12\ndirection = -1\n[walker]\nx = 1\n')
    with pytest.raises(SpecError, match=r"hardware\.servos\.BR_coxa: not in this file's"):
        edit_servos(path, {"BR_coxa": {"direction": -1}})


def test_emulate_serves_the_robot_until_stopped(tmp_path: Path, shc: Shc) -> None:
    robot = _robot(tmp_path, "STS3215")
    link = tmp_path / "bus0"
    process = subprocess.Popen([*SHC, "hw", "emulate", str(robot), "--link", str(link)], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        assert process.stdout is not None
        assert process.stdout.readline().strip() == f"bus 0: {link}"
        result = shc("hw", "scan", "--port", str(link), "--ids", "1-18", "--baud", "1000000", "--protocol",
                     "feetech", "--timeout-ms", "30")
    finally:
        process.terminate()
        process.wait(timeout=30)
    assert result.returncode == 0 and result.stdout.splitlines()[-1] == "18 servos found", result.stdout
    assert process.returncode == 0 and not link.exists()


@pytest.mark.parametrize(("model", "expected"), [
    ("XM430-W350", [(100, 266), (116, 2048), (64, 1), (116, 2048 + 65), (116, 2048), (64, 0), (100, 885)]),
    ("STS3215", [(48, 300), (42, 2048), (40, 1), (42, 2048 + 65), (42, 2048), (40, 0), (48, 1000)]),
])
def test_jog_on_protocol_2_and_feetech_limits_the_torque_and_returns(model: str, expected: list[tuple[int, int]],
                                                                    tmp_path: Path, shc: Shc) -> None:
    """The other families: Protocol 2.0 limits Goal PWM (address 100: 30 % of 885; 885 is the emulator's power-up
    value), Feetech Torque Limit (48: 30 % of 1000); the goal goes 0.1 rad out (4096 ticks a turn: 65 ticks) and
    back, the torque off, the limit restored."""
    robot = _robot(tmp_path, model)
    with EmulatorProcess({k + 1: model for k in range(18)}) as bus:
        result = shc("hw", "jog", str(robot), "--port", bus.port, "--joint", "AR_coxa", "--answers", "y,k")
        packets = bus.packets()
    assert result.returncode == 0, result.stderr
    wide = model.startswith("XM")  # Protocol 2.0: 2-byte addresses
    writes = [(int.from_bytes(p[2][:2], "little"), int.from_bytes(p[2][2:], "little")) if wide else
              (p[2][0], int.from_bytes(p[2][1:], "little")) for p in packets if p[0] == 1 and p[1] == p1.WRITE]
    assert writes == expected, writes


def test_the_emulator_process_answers_for_protocol_2_and_reports_a_wrong_request() -> None:
    with EmulatorProcess({5: "XM430-W350"}) as bus:
        assert bus.position(5) == 2048 and bus.goal(5) == 2048 and not bus.torque_on(5)
        with pytest.raises(RuntimeError, match="the emulator refused goal: KeyError"):
            bus.goal(6)
        assert bus.position(5) == 2048  # still serving


def test_the_emulator_process_reads_and_writes_tables_logs_packets_and_injects_faults() -> None:
    """What the real-time run-hw tests ask of the served emulator (tests/test_run_hw.py, test_run_hw_families.py):
    control-table bytes, the packets heard, a fault with the packet count at that moment, a servo unplugged."""
    from dynamixel_sdk import COMM_RX_TIMEOUT, COMM_SUCCESS, PacketHandler, PortHandler

    class Unhurried(PortHandler):  # type: ignore[misc]
        """The SDK's port with a reply timeout of 2 s instead of ≈ 34 ms: the emulator is a process of its own, which
        a loaded machine leaves unscheduled for longer than that (a read timed out at load 13; issue 42)."""

        def setPacketTimeout(self, packet_length: int) -> None:
            self.setPacketTimeoutMillis(2000.0)

    with EmulatorProcess({1: "MX-106", 2: "MX-106"}) as bus:
        assert bus.ids() == [1, 2] and bus.packet_count() == 0
        assert bus.table(1, 7) == b"\x01" and bus.table(2, 132, 4) == (2048).to_bytes(4, "little")  # id; present
        bus.poke(2, 11, bytes([1]))  # velocity mode
        port = Unhurried(bus.port)
        assert port.openPort() and port.setBaudRate(1_000_000)
        handler = PacketHandler(2.0)
        try:
            assert handler.read1ByteTxRx(port, 2, 11) == (1, COMM_SUCCESS, 0)
            assert handler.write1ByteTxRx(port, 1, 64, 1) == (COMM_SUCCESS, 0)
            assert bus.torque_on(1) and bus.table(1, 64) == b"\x01"
            assert bus.packets(1) == [(1, 0x03, bytes([64, 0, 1]))]  # WRITE: address 64, one byte
            assert bus.packets()[1].params == bytes([64, 0, 1])
            assert bus.fault(1, "hardware_error", 32) == 2
            assert handler.read1ByteTxRx(port, 1, 64)[2] == 0x80  # the alert bit
            assert bus.vanish(2) == 3
            assert handler.ping(port, 2)[1] == COMM_RX_TIMEOUT
            assert handler.ping(port, 1)[1] == COMM_SUCCESS
        finally:
            port.closePort()
        with pytest.raises(RuntimeError, match="no fault 'melted'"):
            bus.fault(1, "melted", True)
        with pytest.raises(RuntimeError, match="outside the table"):
            bus.table(1, 250, 10)


def test_jog_refuses_a_zero_that_puts_the_limits_outside_the_servo_and_validate_agrees(tmp_path: Path,
                                                                                      shc: Shc) -> None:
    """AR_femur's servo stands at tick 800 when its zero is taken "here": its limits ±1.5 rad (±293 AX ticks) would be
    ticks 507..1093, beyond the AX-12A's 0..1023 — a file every later hw check, jog and run-hw refuses. Jog keeps the
    old zero and says so; validate refuses that zero by the same rule."""
    robot = _robot(tmp_path)
    before = robot.read_text()
    with EmulatorProcess({k + 1: "AX-12A" for k in range(18)},
                         positions={**{k + 1: TIBIA_TICKS for k in range(2, 18, 3)}, 2: 800}) as bus:
        result = shc("hw", "jog", str(robot), "--port", bus.port, "--joint", "AR_femur", "--answers", "y,h")
        assert result.returncode == 0, result.stderr
        again = shc("hw", "check", str(robot), "--port", bus.port)
    assert robot.read_text() == before  # nothing to write: the direction was right, the zero refused
    (warning,) = [line for line in result.stderr.splitlines() if line.startswith("warning: AR_femur")]
    zero = int(warning.split()[3])  # where the servo came back to: 800 within the emulator's lag
    assert warning.startswith(f"warning: AR_femur: zero_ticks {zero} not written") and 790 <= zero <= 810
    assert "the joint limits -1.500..1.500 rad are ticks 5" in warning and "outside the AX-12A's 0..1023" in warning
    assert "kept zero_ticks 512" in warning
    assert "outside servo" not in again.stderr, again.stderr
    bad = tmp_path / "bad.toml"
    bad.write_text(before.replace("AR_femur = { id = 2 }", "AR_femur = { id = 2, zero_ticks = 800 }"))
    checked = shc("validate", str(bad))
    assert checked.returncode == 2
    assert (f"{bad}:" in checked.stderr and "hardware.servos.AR_femur.zero_ticks: the joint limits -1.500..1.500 rad "
            "are ticks 507..1093 with zero_ticks 800 and direction +1, outside the AX-12A's 0..1023"
            in checked.stderr), checked.stderr
