"""``docs/performance.md`` is a reference page: one section per command or topic, each naming the command that
measures its figures and the date they were measured; no section titled by an issue or a round; every benchmark
script (and option) it names exists; the figures other pages quote from it are still there."""

from __future__ import annotations

import re
from pathlib import Path

from .conftest import ROOT

PAGE = ROOT / "docs" / "performance.md"

NOTEBOOK_TITLE = re.compile(r"^#+ .*\b([Ii]ssue ?[0-9]+|[Rr]ound)\b")
"""A title of the lab notebook this page was (the same pattern as the project's before-stop hook)."""

DATE = re.compile(r"\b20\d\d-[01]\d-[0-3]\d\b")
COMMAND = re.compile(r"`[^`\n]*(?:\bshc |benchmarks/\w+\.py|pytest)[^`\n]*`")
"""A backticked command: an ``shc`` command, a benchmark script or a pytest run."""
SCRIPT = re.compile(r"benchmarks/(\w+\.py)")
SPAN = re.compile(r"`([^`\n]+)`")


def sections(text: str) -> dict[str, str]:
    """The page's ``## `` sections by title (``### `` parts stay in their section)."""
    return {part.split("\n", 1)[0].strip(): part for part in re.split(r"^## ", text, flags=re.M)[1:]}


def problems(text: str, root: Path) -> list[str]:
    """What keeps ``text`` from being the reference page; empty when nothing does."""
    found = [f"a notebook title: {line}" for line in text.splitlines() if NOTEBOOK_TITLE.match(line)]
    for name in sorted(set(SCRIPT.findall(text))):
        if not (root / "benchmarks" / name).is_file():
            found.append(f"benchmarks/{name} does not exist")
    for span in SPAN.findall(text):
        script = SCRIPT.search(span)
        if script is None or not (root / "benchmarks" / script.group(1)).is_file():
            continue
        source = (root / "benchmarks" / script.group(1)).read_text(encoding="utf-8")
        for option in re.findall(r"(?<![\w-])--[a-z][\w-]*", span[script.end():]):
            if f'"{option}"' not in source:
                found.append(f"benchmarks/{script.group(1)} has no option {option}")
    parts = sections(text)
    if not parts:
        found.append("no section")
    for title, part in parts.items():
        if not COMMAND.search(part):
            found.append(f"section {title!r} names no command")
        if not DATE.search(part):
            found.append(f"section {title!r} gives no date")
    return found


def test_the_page_is_a_reference_page() -> None:
    text = PAGE.read_text(encoding="utf-8")
    assert problems(text, ROOT) == []
    assert len(sections(text)) >= 15  # one per command or topic


def test_the_check_finds_each_kind_of_problem() -> None:
    bad = ("# Performance\n\n## `shc plan` (issue 3)\n\n`shc plan bullet`, 2026-11-22.\n\n"
           "### The loop, fifth round\n\n## Sweep\n\nSomething fast.\n\n"
           "## Loop\n\n`.venv/bin/python benchmarks/bench_nothing.py`, 2026-11-27;"
           " `.venv/bin/python benchmarks/bench_loop.py --repeats 5 --no-such-option`.\n")
    assert problems(bad, ROOT) == [
        "a notebook title: ## `shc plan` (issue 3)",
        "a notebook title: ### The loop, fifth round",
        "benchmarks/bench_nothing.py does not exist",
        "benchmarks/bench_loop.py has no option --no-such-option",
        "section 'Sweep' names no command",
        "section 'Sweep' gives no date",
    ]


QUOTED = {
    "tests/test_run_hw_families.py": "25 Hz",
    "docs/your-robot.md": "25 Hz",
    "docs/commands.md": "First run after the install",
    "README.md": "1 min 56 s",
    "docs/experiments/openshc-cot.md": "13.7 min",
    "shc_cli/view/render.py": "252 ms",
    "shc_cli/domain/warmup.py": "≈ 10 s",
    "docs/fitting-servos.md": "27 %",
}
"""A figure each file quotes from docs/performance.md."""


def _words(path: Path) -> str:
    """The file's text with every run of white space one space (a quote may be wrapped across lines)."""
    return " ".join(path.read_text(encoding="utf-8").split())


def test_the_figures_other_files_quote_are_on_the_page() -> None:
    text = _words(PAGE)
    for quoting, figure in QUOTED.items():
        words = _words(ROOT / quoting)
        assert "performance.md" in words and figure in words, (quoting, figure)
        assert figure in text, f"{quoting} quotes {figure!r} from docs/performance.md"
    assert "≈ 1 ms per servo" in _words(ROOT / "docs" / "commands.md")
    assert "≈ 1 ms behind an FTDI adapter" in text and "24 ms" in text
