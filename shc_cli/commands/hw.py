"""``shc hw scan|check|emulate``: find the servos, check where they stand, emulate a robot's buses
(:mod:`shc_cli.domain.bringup`); ``jog`` is :mod:`shc_cli.commands.hw_jog`. Exit codes: 0 done, 1 ``check`` found
joints outside their limits, 2 bad input, 3 a servo fault (named; the torque is off)."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import typer

T = TypeVar("T")

EXIT_OUTSIDE = 1
"""``shc hw check``: a joint is outside its limits."""


def parse_ids(text: str) -> range:
    """``"1-18"`` or ``"7"`` → the id range (0–252); a bad one is one line, exit 2."""
    from shc_cli.errors import Issue, SpecError

    first, _, last = text.partition("-")
    try:
        ids = range(int(first), int(last or first) + 1)
    except ValueError:
        ids = range(0)
    if not ids or ids.start < 0 or ids.stop > 253:
        raise SpecError([Issue(None, None, "--ids", f"{text!r} is not an id range", "give FIRST-LAST within 0-252, "
                                                                                    "e.g. 1-18")])
    return ids


def run_scan(ports: list[str], bauds: list[int], protocols: list[str], ids: str, timeout_ms: float | None) -> None:
    """Print one line per servo found (port, baud, protocol, id, model, firmware)."""
    from shc_cli.api import hw_scan
    from shc_cli.errors import Issue, SpecError
    from shc_cli.hardware.scan import PROTOCOLS, Protocol

    wrong = [p for p in protocols if p not in PROTOCOLS]
    if wrong:
        raise SpecError([Issue(None, None, "--protocol", f"{wrong[0]!r} is not a protocol",
                               f"give {', '.join(PROTOCOLS)}")])
    chosen: list[Protocol] = [p for p in PROTOCOLS if p in protocols]
    found = hw_scan(ports, bauds=bauds or None, protocols=chosen or None, ids=parse_ids(ids),
                    timeout_s=None if timeout_ms is None else timeout_ms / 1000.0)
    if not found:
        typer.echo("no servo answered")
        return
    typer.echo(f"{'port':<16} {'baud':>8}  {'protocol':<8} {'id':>3}  {'model':<14} firmware")
    for servo in found:
        typer.echo(f"{servo.port:<16} {servo.baud:>8}  {servo.protocol:<8} {servo.servo_id:>3}  {servo.model:<14} "
                   f"{servo.firmware}")
    typer.echo(f"{len(found)} servo{'s' if len(found) > 1 else ''} found")


def run_check(robot: str, ports: list[str], baud: int | None) -> None:
    """Print the table; exit 1 when a joint is outside its limits, 3 on a servo fault."""
    from shc_cli.api import hw_check

    report = faults_exit_3(lambda: hw_check(robot, ports, baud))
    typer.echo(f"{'joint':<14} {'id':>3} {'ticks':>6} {'angle°':>8} {'min°':>8} {'max°':>8} {'standing°':>10} "
               f"{'Δstand°':>8}  status")
    for r in report.readings:
        status = "ok" if r.within else f"OUTSIDE by {math.degrees(r.outside_by):.1f}°"
        typer.echo(f"{r.joint:<14} {r.servo_id:>3} {r.ticks:>6} {math.degrees(r.angle):>8.1f} "
                   f"{math.degrees(r.low):>8.1f} {math.degrees(r.high):>8.1f} {math.degrees(r.standing):>10.1f} "
                   f"{math.degrees(r.angle - r.standing):>8.1f}  {status}")
    outside = report.outside
    if outside:
        typer.echo(f"{len(outside)} joint{'s' if len(outside) > 1 else ''} outside the limits: "
                   f"{', '.join(r.joint for r in outside)} (move them by hand, torque off, or fix zero_ticks and "
                   "direction with shc hw jog)", err=True)
        raise typer.Exit(EXIT_OUTSIDE)
    typer.echo(f"{report.robot}: every joint within its limits")


def faults_exit_3(call: Callable[[], T]) -> T:
    """``call()``; a servo fault is one line naming the servo and exit 3."""
    from shc_cli.commands.outcome import EXIT_FAULT
    from shc_cli.hardware.servo_io import ServoFault

    try:
        return call()
    except ServoFault as fault:
        typer.echo(f"fault: {fault} (torque off)", err=True)
        raise typer.Exit(EXIT_FAULT) from None


def run_emulate(robot: str, links: list[Path], baud: int | None, duration: float | None,
                dynamics: bool = False) -> None:
    """Print each bus's port (bus 0 first) once it answers, then serve until Ctrl-C."""
    from shc_cli.api import hw_emulate

    def ready(ports: list[str]) -> None:
        for bus, port in enumerate(ports):
            typer.echo(f"bus {bus}: {port}")
        typer.echo("emulating until Ctrl-C", err=True)

    hw_emulate(robot, ready, links=links, baud=baud, duration=duration, dynamics=dynamics)
