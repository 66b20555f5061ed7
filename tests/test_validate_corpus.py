"""``shc validate`` on a corpus of broken files: one mistake each, reported as exactly one line.

Every ``tests/corpus/robot_*.toml`` and ``tests/corpus/gait_*.toml`` holds ONE deliberate mistake,
as a user would make it, and starts with header comments:

    # case: what is wrong, in words
    # expect: a substring of the error line
    # args: companion files passed before it (optional; names inside tests/corpus)
    # line: the line the error must name, or "none" when there is none (e.g. a missing key)

``base_*.toml`` files are companions: valid robots and gaits that cases extend or are checked
against (first line ``# Companion (valid): ...``), or the other half of a circular ``extends``.

The CLI runs in-process (``shc_cli.cli.main`` with a patched ``sys.argv``) so the corpus stays fast.
"""

from __future__ import annotations

import re
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from shc_cli import cli

CORPUS = Path(__file__).parent / "corpus"
HEADER = re.compile(r"# (case|expect|args|line): (.*)")
MIN_CASES = 100


@dataclass(frozen=True)
class Case:
    """One broken file and what ``shc validate`` must say about it."""

    path: Path
    about: str
    expect: str
    args: tuple[str, ...]
    line: int | None


def _case(path: Path) -> Case:
    header: dict[str, str] = {}
    for text in path.read_text(encoding="utf-8").splitlines():
        match = HEADER.fullmatch(text)
        if match is None:
            break
        header[match.group(1)] = match.group(2).strip()
    missing = {"case", "expect", "line"} - set(header)
    if missing:
        raise ValueError(f"{path.name}: header lacks {', '.join(sorted(missing))}")
    line = None if header["line"] == "none" else int(header["line"])
    return Case(path, header["case"], header["expect"], tuple(header.get("args", "").split()), line)


CASE_FILES = sorted([*CORPUS.glob("robot_*.toml"), *CORPUS.glob("gait_*.toml")])
CASES = [_case(path) for path in CASE_FILES]
VALID_COMPANIONS = sorted(
    path for path in CORPUS.glob("base_*.toml")
    if path.read_text(encoding="utf-8").startswith("# Companion (valid)")
)


def _run_validate(files: list[str], monkeypatch: pytest.MonkeyPatch,
                  capsys: pytest.CaptureFixture[str]) -> tuple[object, str, str]:
    """(exit code, stdout, stderr) of ``shc validate FILES`` run in this process."""
    monkeypatch.setattr(sys, "argv", ["shc", "validate", *files])
    with pytest.raises(SystemExit) as exit_info:
        cli.main()
    captured = capsys.readouterr()
    return exit_info.value.code, captured.out, captured.err


def test_corpus_has_enough_cases() -> None:
    assert len(CASES) >= MIN_CASES, f"only {len(CASES)} cases in {CORPUS}"


def test_every_case_names_existing_companions() -> None:
    absent = [f"{case.path.name}: {arg}" for case in CASES for arg in case.args if not (CORPUS / arg).is_file()]
    assert not absent, absent


def test_expectations_are_unique_files() -> None:
    names = [case.path.name for case in CASES]
    assert len(names) == len(set(names))
    assert all(case.expect for case in CASES)


@pytest.mark.parametrize("path", VALID_COMPANIONS, ids=lambda path: path.stem)
def test_valid_companion_passes(path: Path, monkeypatch: pytest.MonkeyPatch,
                                capsys: pytest.CaptureFixture[str]) -> None:
    """The files the cases build on are valid, so each case's one edit is its only mistake."""
    code, out, err = _run_validate([str(path)], monkeypatch, capsys)
    assert code == 0, err
    assert err == ""
    assert "ok" in out or "legs," in out


@pytest.mark.parametrize("case", CASES, ids=lambda case: case.path.stem)
def test_broken_file_gives_one_error_line(case: Case, monkeypatch: pytest.MonkeyPatch,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = _run_validate([*(str(CORPUS / arg) for arg in case.args), str(case.path)],
                                   monkeypatch, capsys)
    assert "Traceback" not in out + err
    assert out == ""
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, f"{case.about}: expected one error line, got:\n" + "\n".join(lines)
    line = lines[0]
    assert code == 2, line
    assert line.startswith(f"error: {case.path}"), line
    where = f"error: {case.path}:{case.line}: " if case.line is not None else f"error: {case.path}: "
    assert line.startswith(where), f"{case.about}: expected it to start with {where!r}, got {line!r}"
    assert case.expect in line, f"{case.about}: {case.expect!r} not in {line!r}"
