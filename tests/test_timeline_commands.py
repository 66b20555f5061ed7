"""A timeline's commands are made on demand: the same commands as the list of every cycle, in memory that does not
grow with the run's length (``--duration 36000`` once held 3.6 million commands before the first step)."""

from __future__ import annotations

import tracemalloc

from hypothesis import given, settings
from hypothesis import strategies as st

from shc_cli.control.controller import Command
from shc_cli.loop.input_sources import timeline_commands
from shc_cli.spec.timeline import EVENTS, Timeline, constant


def every_cycle(changes: list[tuple[int, dict[str, object]]], cycles: int) -> list[Command]:
    """The per-cycle list, written out as the timeline's rule says (changes hold from their cycle; one-off
    requests only at it)."""
    out = []
    for cycle in range(cycles):
        held: dict[str, object] = {}
        events: dict[str, object] = {}
        for at, change in sorted(changes, key=lambda c: c[0]):
            if at <= cycle:
                held.update({k: v for k, v in change.items() if k not in EVENTS})
            if max(at, 0) == cycle:
                events.update({k: v for k, v in change.items() if k in EVENTS})
        out.append(Command(**held, **events))  # type: ignore[arg-type]
    return out


change = st.fixed_dictionaries({}, optional={
    "velocity": st.tuples(*[st.floats(-1, 1)] * 3),
    "cruise": st.booleans(),
    "leg_toggle": st.sampled_from(["AR", "BL"]),
    "parameters": st.dictionaries(st.sampled_from(["step_frequency", "swing_height"]), st.floats(0.1, 2), max_size=1),
})


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(st.integers(-3, 40), change), max_size=6), st.integers(0, 45))
def test_commands_on_demand_equal_the_list_of_every_cycle(changes: list[tuple[int, dict[str, object]]],
                                                          cycles: int) -> None:
    made = timeline_commands(Timeline(changes), cycles)
    expected = every_cycle(changes, cycles)
    assert len(made) == cycles
    assert list(made) == expected
    assert made[-1:] == expected[-1:]


def test_a_ten_hour_timeline_holds_no_command_per_cycle() -> None:
    tracemalloc.start()
    try:
        commands = timeline_commands(constant((0.5, 0.0, 0.0)), 3_600_000)  # 10 h at 100 Hz
        last = commands[len(commands) - 1]
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert last == Command(velocity=(0.5, 0.0, 0.0)) and commands[0] == last
    assert peak < 100_000, f"{peak} bytes for the commands of 3.6 million cycles"
