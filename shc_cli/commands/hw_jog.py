"""``shc hw jog``: each joint moved a little and back; the user's answers (asked here, or given with
``--answers``) about direction and zero are written to the robot file (:mod:`shc_cli.domain.bringup.jog`)."""

from __future__ import annotations

import sys

import typer

from shc_cli.commands.hw import faults_exit_3


def run_jog(robot: str, ports: list[str], joints: list[str], angle: float, torque: float, answers: str | None,
            baud: int | None) -> None:
    """Jog, asking each question (the next of ``answers`` when given, else on the terminal); print what was
    written."""
    from shc_cli.api import hw_jog
    from shc_cli.domain.bringup.jog import Question
    from shc_cli.errors import Issue, SpecError

    given = [a.strip().lower() for a in answers.split(",")] if answers else []

    def ask(question: Question) -> str:
        typer.echo(question.text)
        if given:
            answer = given.pop(0)
            typer.echo(f"> {answer}")
        elif sys.stdin.isatty():
            answer = typer.prompt(">", default="", show_default=False).strip().lower()
        else:  # answers piped in, one a line
            answer = sys.stdin.readline().strip().lower()
            if not answer:
                raise SpecError([Issue(None, None, "--answers", f"no answer for {question.joint}'s question (end of "
                                       "input); nothing written", "give one answer per question, e.g. --answers y,k")])
            typer.echo(f"> {answer}")
        answer = answer[:1]
        if answer not in question.choices:
            raise SpecError([Issue(None, None, "--answers", f"{answer!r} answers none of {question.joint}'s choices "
                                   f"({'/'.join(question.choices)}); nothing written", "run jog again")])
        return answer

    report = faults_exit_3(lambda: hw_jog(robot, ports, ask, joints=joints or None, angle=angle, torque=torque,
                                          baud=baud))
    if given:
        typer.echo(f"warning: {len(given)} answers left over", err=True)
    for joint, fields in report.changes.items():
        typer.echo(f"{joint}: " + ", ".join(f"{name} = {value}" for name, value in fields.items()))
    typer.echo(f"{len(report.moves)} joints jogged, {len(report.changes)} changed in {report.path}"
               if report.changes else f"{len(report.moves)} joints jogged, {report.path} unchanged")
