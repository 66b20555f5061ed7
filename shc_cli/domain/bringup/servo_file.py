"""Writing confirmed servo settings (``direction``, ``zero_ticks``) back into a robot file's ``[hardware.servos]``
table, the rest of the file as it was: each joint's entry is edited where it is (an inline table
``AR_coxa = { id = 11, … }`` or a ``[hardware.servos.AR_coxa]`` table), comments and order kept. The new text is
parsed and loaded as a robot before it replaces the file (atomically: a temporary file renamed over it), so the
file is never half-written.
"""

from __future__ import annotations

import os
import re
import tempfile
import tomllib
from pathlib import Path
from typing import Any

from shc_cli.errors import Issue, SpecError

SECTION = re.compile(r"^\s*\[([^\]]+)\]\s*(#.*)?$")


def _value(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value)
    return '"' + str(value).replace("\\", "\\\\").replace('"', '\\"') + '"'


def _inline(key: str, entry: dict[str, Any], comment: str) -> str:
    body = ", ".join(f"{name} = {_value(value)}" for name, value in entry.items())
    return f"{key} = {{ {body} }}" + (f"  {comment}" if comment else "")


def _refuse(path: Path, key: str, why: str) -> SpecError:
    return SpecError([Issue(path, None, f"hardware.servos.{key}", why,
                            "write the joint's entry in this file (its ids from the parent file) and run jog again")])


def edit_servos(path: Path, changes: dict[str, dict[str, int]]) -> str:
    """The text of the robot file ``path`` with ``changes`` (joint key → {field: value}) applied to its
    ``[hardware.servos]`` entries. Raises :class:`SpecError` when a joint's entry is not in this file (e.g.
    inherited through ``extends``)."""
    lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
    section = ""
    done: set[str] = set()
    sub_tables: dict[str, int] = {}  # [hardware.servos.KEY] → the line after its header
    for number, line in enumerate(lines):
        header = SECTION.match(line)
        if header:
            section = header.group(1).strip()
            if section.startswith("hardware.servos."):
                sub_tables[section.removeprefix("hardware.servos.").strip('"')] = number + 1
            continue
        if section != "hardware.servos":
            continue
        match = re.match(r'^(\s*)("?)([\w.-]+)\2\s*=\s*(\{.*\})\s*(#.*)?$', line.rstrip("\n"))
        if not match or match.group(3) not in changes:
            continue
        key = match.group(3)
        entry = tomllib.loads(f"x = {match.group(4)}")["x"]
        entry.update(changes[key])
        ending = "\n" if line.endswith("\n") else ""
        lines[number] = match.group(1) + _inline(match.group(2) + key + match.group(2), entry,
                                                 match.group(5) or "") + ending
        done.add(key)
    for key, start in sorted(sub_tables.items(), key=lambda item: -item[1]):
        if key not in changes or key in done:
            continue
        end = next((n for n in range(start, len(lines)) if SECTION.match(lines[n])), len(lines))
        for name, value in changes[key].items():
            at = next((n for n in range(start, end) if re.match(rf"^\s*{name}\s*=", lines[n])), None)
            text = f"{name} = {_value(value)}\n"
            if at is None:
                lines.insert(start, text)
                end += 1
            else:
                lines[at] = text
        done.add(key)
    missing = sorted(set(changes) - done)
    if missing:
        raise _refuse(path, missing[0], "not in this file's [hardware.servos] table (inherited through extends?)")
    return "".join(lines)


def write_servos(path: Path, changes: dict[str, dict[str, int]]) -> None:
    """Apply ``changes`` to the robot file ``path`` (see :func:`edit_servos`), checked and atomically."""
    from shc_cli.spec.loading import load_robot

    if not changes:
        return
    text = edit_servos(path, changes)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".toml", dir=path.parent)
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as out:
            out.write(text)
        servos = load_robot(temporary).robot.hardware.servos
        for key, fields in changes.items():
            for name, value in fields.items():
                if getattr(servos[key], name) != value:
                    raise SpecError([Issue(path, None, f"hardware.servos.{key}.{name}",
                                           f"the edited file reads {getattr(servos[key], name)}, not {value}")])
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.unlink(temporary)
