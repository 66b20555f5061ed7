"""``run-hw``'s live inputs without devices: gamepad events, keys and JSON lines → the held command."""

from __future__ import annotations

import io
import threading
import time

import pytest
from evdev import AbsInfo, ecodes

from shc_cli.control.controller import RobotState
from shc_cli.loop.input_sources import KEYS, GamepadMapping, HeldInput, StdinInput
from shc_cli.spec.loading import load_gait


def _pad() -> GamepadMapping:
    """An 8-bit-stick gamepad as evdev describes it (0..255, centre 128)."""
    info = AbsInfo(value=128, min=0, max=255, fuzz=0, flat=15, resolution=0)
    return GamepadMapping({ecodes.EV_ABS: [(code, info) for code in (ecodes.ABS_X, ecodes.ABS_Y, ecodes.ABS_RX,
                                                                      ecodes.ABS_RY)]})


def _apply(held: HeldInput, mapping: GamepadMapping, kind: int, code: int, value: int) -> None:
    change = mapping.change(kind, code, value)
    assert change is not None, (kind, code, value)
    held.update(change)


def test_gamepad_sticks_scale_by_the_device_range_with_a_dead_zone() -> None:
    mapping, held = _pad(), HeldInput()
    _apply(held, mapping, ecodes.EV_ABS, ecodes.ABS_Y, 0)  # left stick fully up: forward
    _apply(held, mapping, ecodes.EV_ABS, ecodes.ABS_X, 255)  # fully right: strafe right (−y)
    _apply(held, mapping, ecodes.EV_ABS, ecodes.ABS_RX, 64)  # right stick half left: turn left (+yaw)
    command = held.next()
    assert command is not None
    assert command.velocity == pytest.approx((1.0, -1.0, 0.498), abs=1e-3)
    _apply(held, mapping, ecodes.EV_ABS, ecodes.ABS_Y, 140)  # within 10 % of the centre: 0
    _apply(held, mapping, ecodes.EV_ABS, ecodes.ABS_RY, 255)  # right stick down: body pitch
    command = held.next()
    assert command is not None and command.velocity[0] == 0.0 and command.pose_velocity[4] == -1.0
    assert mapping.axis(ecodes.ABS_Y, 999) == 1.0  # out-of-range values are clamped


def test_gamepad_buttons_set_state_gait_and_stop() -> None:
    mapping = _pad()
    gaits = [load_gait(name).gait for name in ("tripod", "wave")]
    held = HeldInput([g for g in gaits if g is not None])
    assert mapping.change(ecodes.EV_KEY, ecodes.BTN_SELECT, 0) is None  # releases change nothing
    _apply(held, mapping, ecodes.EV_KEY, ecodes.BTN_SELECT, 1)
    assert held.state == RobotState.PACKED
    _apply(held, mapping, ecodes.EV_KEY, ecodes.BTN_NORTH, 1)
    assert held.state.name == "READY"
    _apply(held, mapping, ecodes.EV_KEY, ecodes.BTN_START, 1)
    _apply(held, mapping, ecodes.EV_KEY, ecodes.BTN_SOUTH, 1)  # next gait: a one-off request
    first, second = held.next(), held.next()
    assert first is not None and first.gait is not None and first.gait.name == "wave"
    assert first.state_request == RobotState.RUNNING and second is not None and second.gait is None
    _apply(held, mapping, ecodes.EV_KEY, ecodes.BTN_MODE, 1)
    assert held.next() is None


def test_keys_nudge_and_clamp_the_velocity() -> None:
    held = HeldInput()
    for key in "wwwaq" + "w" * 20:
        held.update(KEYS[key])
    assert held.velocity == [1.0, 0.1, 0.1]  # clamped to full input
    held.update(KEYS["s"])
    held.update(KEYS["1"])
    assert held.velocity[0] == pytest.approx(0.9) and held.state == RobotState.PACKED
    held.update(KEYS["r"])
    assert held.pose_velocity[2] == 0.5
    held.update(KEYS[" "])
    held.update(KEYS["x"])
    assert held.velocity == [0.0, 0.0, 0.0] and held.pose_velocity == [0.0] * 6 and held.next() is None


def test_stdin_lines_hold_until_changed_and_the_watchdog_zeroes_the_velocity() -> None:
    lines = io.StringIO('{"velocity": [0.5, 0, 0.1], "pose_velocity": [0, 0, 1, 0, 0, 0]}\n{"state": "ready"}\n'
                        '{"state": "flying"}\n{"gait": "wave"}\n')
    source = StdinInput(lines, watchdog_s=0.2, load_gait=lambda name: load_gait(name).gait)
    deadline = time.monotonic() + 60.0  # only a failure waits this long (a loaded machine may take seconds)
    while not source.finished and time.monotonic() < deadline:
        time.sleep(0.01)
    assert source.finished and source.next() is None  # end of input
    assert source.velocity == [0.5, 0.0, 0.1] and source.pose_velocity[2] == 1.0
    assert source.state == RobotState.READY  # the "flying" line was ignored
    assert source.gait is not None and source.gait.name == "wave"
    now = [100.0]  # an injected clock [s]: the watchdog is tested without waiting
    held = StdinInput(io.StringIO(""), watchdog_s=0.05, clock=lambda: now[0])
    held.finished = False
    held.update(lambda h: setattr(h, "velocity", [1.0, 0.0, 0.0]))
    now[0] += 0.04
    command = held.next()
    assert command is not None and command.velocity == (1.0, 0.0, 0.0)
    now[0] += 0.02
    command = held.next()
    assert command is not None and command.velocity == (0.0, 0.0, 0.0) and held.watchdog_trips == 1


def test_stdin_parse_validates_before_applying() -> None:
    source = StdinInput(io.StringIO(""), load_gait=lambda name: load_gait(name).gait)
    held = HeldInput()
    source._parse('{"velocity": [0.5, 0, 0.1], "state": "packed", "gait": "wave"}')(held)
    assert held.velocity == [0.5, 0.0, 0.1] and held.state == RobotState.PACKED
    assert held.gait is not None and held.gait.name == "wave"
    for bad, message in (('{"velocity": [1, 2]}', "3 numbers"), ('{"state": "flying"}', "packed, ready, running"),
                         ('{"speed": 1}', "unknown key 'speed'"), ("[1, 2]", "not an object")):
        with pytest.raises(ValueError, match=message):
            source._parse(bad)


def test_a_gait_for_other_legs_is_refused_on_stdin(monkeypatch: pytest.MonkeyPatch) -> None:
    """The stdin gait loader of run-hw and simulate refuses a gait for another leg set (the line is ignored with a
    warning)."""
    import sys

    from shc_cli.loop.input_choice import open_input

    monkeypatch.setattr(sys, "stdin", io.StringIO(""))
    from shc_cli.errors import SpecError
    from shc_cli.spec.loading import load_robot

    robot, gait = load_robot("bullet").robot, load_gait("tripod").gait
    source = open_input("stdin", robot, gait, [], 0.5)
    assert isinstance(source, StdinInput) and source.load_gait is not None
    with pytest.raises(SpecError, match="gait 'quad_wave' is for legs"):
        source.load_gait("quad_wave")
    assert source.load_gait("wave").name == "wave"


class _FakeGamepad:
    """An evdev InputDevice stand-in: sticks and buttons, a few events, then unplugged (OSError) once the test has
    read the command (:attr:`unplug` set)."""

    unplug = threading.Event()

    def __init__(self, path: str) -> None:
        self.path, self.name, self.closed = path, "Fake Pad", False

    def capabilities(self, absinfo: bool = True) -> dict[int, list[object]]:
        info = AbsInfo(value=128, min=0, max=255, fuzz=0, flat=15, resolution=0)
        return {ecodes.EV_ABS: [(ecodes.ABS_X, info), (ecodes.ABS_Y, info)],
                ecodes.EV_KEY: [ecodes.BTN_SOUTH, ecodes.BTN_START]}

    def read_loop(self) -> object:
        from evdev import InputEvent

        yield InputEvent(0, 0, ecodes.EV_ABS, ecodes.ABS_Y, 0)  # full forward
        yield InputEvent(0, 0, ecodes.EV_KEY, ecodes.BTN_SELECT, 1)  # packed
        self.unplug.wait(timeout=5.0)
        raise OSError(19, "No such device")  # unplugged

    def close(self) -> None:
        self.closed = True


class _Keyboard(_FakeGamepad):
    def capabilities(self, absinfo: bool = True) -> dict[int, list[object]]:
        return {ecodes.EV_KEY: [ecodes.KEY_A]}


def test_gamepad_is_found_read_and_its_loss_stops_the_robot(monkeypatch: pytest.MonkeyPatch,
                                                            caplog: pytest.LogCaptureFixture) -> None:
    import evdev

    from shc_cli.loop.input_sources import GamepadInput, InputError

    _FakeGamepad.unplug.clear()
    monkeypatch.setattr(evdev, "list_devices", lambda: ["/dev/input/event3", "/dev/input/event7"])
    monkeypatch.setattr(evdev, "InputDevice", lambda path: (_Keyboard if path.endswith("3") else _FakeGamepad)(path))
    pad = GamepadInput()  # the keyboard (no sticks) is skipped
    assert pad.device.path == "/dev/input/event7"
    deadline = time.monotonic() + 60.0  # only a failure waits this long (a loaded machine may take seconds)
    while pad.state != RobotState.PACKED and time.monotonic() < deadline:
        time.sleep(0.01)
    command = pad.next()
    assert command is not None and command.velocity[0] == 1.0 and command.state_request == RobotState.PACKED
    _FakeGamepad.unplug.set()  # now unplug it
    while not pad.finished and time.monotonic() < deadline:
        time.sleep(0.01)
    assert pad.next() is None  # unplugged: the input is over, run-hw stops and shuts down
    assert "the gamepad is gone" in caplog.text  # logged: stderr and the run's events.log
    pad.close()
    monkeypatch.setattr(evdev, "list_devices", lambda: ["/dev/input/event3"])
    with pytest.raises(InputError, match="no gamepad found"):
        GamepadInput()
