"""Reading TOML files while remembering where every value came from.

``tomllib`` gives values but no line numbers. :func:`key_lines` scans the text once and maps
each dotted key path to the line that sets it, so any later error (schema or semantic) can be
reported as ``FILE:LINE: field.path: problem``. Values are wrapped in :class:`Sourced` leaves
while files are merged (``extends``), templated and mirrored, so an error in an expanded leg
points at the line the user actually wrote.
"""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from shc_cli.errors import Issue, SpecError

KeyPath = tuple[str | int, ...]

_BARE = r"[A-Za-z0-9_-]+"
_QUOTED = r'"(?:[^"\\]|\\.)*"|\'[^\']*\''
_KEY = rf"(?:{_BARE}|{_QUOTED})"
_DOTTED = rf"{_KEY}(?:\s*\.\s*{_KEY})*"
_HEADER = re.compile(rf"^\s*(\[\[?)\s*({_DOTTED})\s*\]\]?")
_ASSIGN = re.compile(rf"\s*({_DOTTED})\s*=\s*")


def _split_dotted(text: str) -> list[str]:
    return [k.strip().strip("\"'") for k in re.findall(_KEY, text)]


@dataclass(frozen=True)
class Origin:
    """Where a value was written: the file and the key path inside that file."""

    file: Path
    path: KeyPath


@dataclass(frozen=True)
class Sourced:
    """A leaf value with its origin, used while files are merged and expanded."""

    value: Any
    origin: Origin


def _inline_keys(text: str, start: int, prefix: KeyPath, line: int, out: dict[KeyPath, int]) -> None:
    """Record the keys of an inline table starting at ``text[start] == '{'`` (nested too)."""
    depth_stack: list[KeyPath] = [prefix]
    i = start + 1
    expect_key = True
    while i < len(text) and depth_stack:
        ch = text[i]
        if ch in "\"'":
            end = text.find(ch, i + 1)
            if end < 0:
                return
            if expect_key:
                m = _ASSIGN.match(text, i)
                if m:
                    path = depth_stack[-1] + tuple(_split_dotted(m.group(1)))
                    out.setdefault(path, line)
                    i = m.end()
                    expect_key = False
                    if i < len(text) and text[i] == "{":
                        depth_stack.append(path)
                        expect_key = True
                        i += 1
                    continue
            i = end + 1
            continue
        if ch == "}":
            depth_stack.pop()
            expect_key = False
        elif ch == ",":
            expect_key = True
        elif expect_key and not ch.isspace():
            m = _ASSIGN.match(text, i)
            if m:
                path = depth_stack[-1] + tuple(_split_dotted(m.group(1)))
                out.setdefault(path, line)
                i = m.end()
                expect_key = False
                if i < len(text) and text[i] == "{":
                    depth_stack.append(path)
                    expect_key = True
                    i += 1
                continue
        i += 1


def key_lines(text: str) -> dict[KeyPath, int]:
    """Map every key path set in a TOML document to its 1-based line.

    Tables give the line of their header; ``[[array]]`` entries are indexed in order.
    Multi-line arrays are attributed to the line of their key, which is what a user needs.
    """
    out: dict[KeyPath, int] = {}
    table: KeyPath = ()
    array_counts: dict[KeyPath, int] = {}
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0] if '"' not in raw and "'" not in raw else raw
        header = _HEADER.match(line)
        if header:
            keys = tuple(_split_dotted(header.group(2)))
            if header.group(1) == "[[":
                index = array_counts.get(keys, 0)
                array_counts[keys] = index + 1
                table = (*keys, index)
            else:
                table = keys
            for depth in range(1, len(table) + 1):  # [legs.AR] also writes legs, if nothing did before
                out.setdefault(table[:depth], number)
            continue
        assign = _ASSIGN.match(line)
        if assign and not line.lstrip().startswith(("]", "}", ",")):
            path = table + tuple(_split_dotted(assign.group(1)))
            for depth in range(len(table) + 1, len(path) + 1):
                out.setdefault(path[:depth], number)
            rest = assign.end()
            if rest < len(line) and line[rest] == "{":
                _inline_keys(line, rest, path, number, out)
    return out


def line_of(lines: dict[KeyPath, int], path: KeyPath) -> int | None:
    """Line of ``path``, or of its closest written ancestor."""
    for depth in range(len(path), 0, -1):
        found = lines.get(path[:depth])
        if found is not None:
            return found
    return None


class Document:
    """One parsed TOML file: its data and its key-to-line map."""

    def __init__(self, path: Path) -> None:
        self.path = path
        try:
            text = path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise SpecError([Issue(path, None, "", "file not found", "check the path")]) from None
        except (OSError, UnicodeDecodeError) as error:
            raise SpecError([Issue(path, None, "", f"cannot read file: {error}", "")]) from None
        try:
            self.data: dict[str, Any] = tomllib.loads(text)
        except tomllib.TOMLDecodeError as error:
            message = str(error)
            match = re.search(r"\(at line (\d+), column \d+\)", message)
            line = int(match.group(1)) if match else None
            problem = re.sub(r"\s*\(at line \d+, column \d+\)", "", message)
            problem = problem[0].lower() + problem[1:] if problem else "invalid TOML"
            raise SpecError(
                [Issue(path, line, "", f"TOML syntax error: {problem}", "see https://toml.io for the syntax")]
            ) from None
        self.lines = key_lines(text)

    def line(self, path: KeyPath) -> int | None:
        return line_of(self.lines, path)

    def sourced(self) -> dict[str, Any]:
        """The data with every leaf wrapped in :class:`Sourced` (lists are leaves)."""
        wrapped: dict[str, Any] = _wrap(self.data, self.path, ())
        return wrapped


def _wrap(value: Any, file: Path, path: KeyPath) -> Any:
    if isinstance(value, dict):
        return {k: _wrap(v, file, (*path, k)) for k, v in value.items()}
    return Sourced(value, Origin(file, path))


def unwrap(value: Any) -> Any:
    """Strip :class:`Sourced` wrappers, giving plain TOML data."""
    if isinstance(value, dict):
        return {k: unwrap(v) for k, v in value.items()}
    if isinstance(value, Sourced):
        return value.value
    return value


def origins(value: Any, path: KeyPath = ()) -> dict[KeyPath, Origin]:
    """Map every leaf path of a sourced tree to its origin."""
    out: dict[KeyPath, Origin] = {}
    if isinstance(value, dict):
        for k, v in value.items():
            out.update(origins(v, (*path, k)))
    elif isinstance(value, Sourced):
        out[path] = value.origin
    return out


def deep_merge(base: dict[str, Any], override: dict[str, Any]) -> dict[str, Any]:
    """Merge ``override`` into ``base`` recursively; tables merge, everything else replaces."""
    merged = dict(base)
    for key, value in override.items():
        if isinstance(value, dict) and isinstance(merged.get(key), dict):
            merged[key] = deep_merge(merged[key], value)
        else:
            merged[key] = value
    return merged
