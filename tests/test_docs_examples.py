"""Every shell example of the README and of ``docs/`` runs, as written, in a fresh clone.

What counts as an example (:func:`steps`):

* every command of a ```` ```sh ```` block (a line ending in ``\\`` continues on the next);
* every ``$ `` line of a ```` ```text ```` block (a transcript: the lines after it are its output; an output that
  starts with ``error:`` shows a refusal, so the command must exit 2);
* a ```` ```python ```` block of the README (run with the environment's ``python``);
* a code block right after an ``<!-- file: NAME -->`` comment is a file a tutorial has the reader write: it is
  written to ``NAME`` at that point, before the commands after it run.

The README's first five minutes run after the README's own set-up command in a fresh clone (fast: no ``slow``
marker; about 1–2 minutes). The README and every page of ``docs/`` then run in reading order in one fresh clone,
with the test environment's ``.venv/bin`` first on ``PATH`` (``slow``): a page may neither depend on nor be stopped
by what an earlier page left behind. Runs are shortened by ``SHC_MAX_DURATION``
(:data:`shc_cli.loop.run_inputs.MAX_DURATION_ENV`), which cuts every run to :data:`MAX_DURATION_S` after its
start-up; the docs themselves are run as written. :data:`EXEMPT` lists the commands that are not run, each with its
reason; an unlabelled code block may not hold a command (label it ``sh`` or ``text``).
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

import pytest

from shc_cli.loop.run_inputs import MAX_DURATION_ENV

from .conftest import ROOT
from .test_readme_setup import setup_commands

MAX_DURATION_S = 1.0
"""Seconds after start-up every documented run is cut to (``SHC_MAX_DURATION``)."""

EXEMPT: dict[str, str] = {
    "shc view": "serves a page until Ctrl-C; tests/test_view.py drives it in Chromium",
    "rosbag record": "needs ROS 1 and a running OpenSHC",
    "optuna-dashboard": "serves a page until Ctrl-C",
    "taplo check": "taplo is an editor tool, not installed here (tests/test_robot_files.py checks the schema)",
    "shc ros2": "needs the ros2 extra and a ROS 2 peer (tests/test_ros2.py drives it with an rclpy node)",
    "shc ros": "needs a ROS 1 master (tests/test_ros_session.py runs it against Debian's roscore)",
    "rosparam": "needs a ROS 1 master (tests/test_ros_node.py reads rosparam values)",
    "rostopic pub": "needs a ROS 1 master and shc ros running (tests/test_path_ros.py publishes a goal with it)",
    "shc run-hw": "needs the robot's servos (tests/test_run_hw.py runs it against the servo emulator)",
    "shc hw": "needs the robot's servos (tests/test_howto_your_robot.py runs docs/your-robot.md against emulated "
              "buses)",
}
"""Command prefixes that are not run, and why."""

UNCUT: dict[str, str] = {
    "python-api.md": "its example prints the plan's stance-feet speed, which a plan cut to 1 s has not got (20 s "
                     "uncut; tests/test_python_api.py runs it too)",
}
"""Pages whose ``python`` blocks run without ``SHC_MAX_DURATION``, and why."""

FILE_MARK = re.compile(r"<!--\s*file:\s*(\S+)\s*-->\s*\n *```\w*\n")
BLOCK = re.compile(r"^( *)```(\w*)\n(.*?)^\1```", re.S | re.M)
"""A fenced code block, also indented under a list item: indent, language, body."""


@dataclass(frozen=True)
class Step:
    """One thing a page has the reader do: ``kind`` is ``run``, ``refuse`` (must exit 2), ``python`` or ``file``."""

    kind: str
    text: str
    where: str
    name: str = ""


def _commands(block: str) -> list[tuple[int, str]]:
    """The commands of a ``sh`` block with their line in it: comment-only and blank lines dropped, ``\\``
    continuations joined."""
    commands: list[tuple[int, str]] = []
    pending, start = "", 0
    for number, line in enumerate(block.splitlines()):
        if not pending and (not line.strip() or line.lstrip().startswith("#")):
            continue
        if not pending:
            start = number
        pending = f"{pending}\n{line}" if pending else line
        if not line.endswith("\\"):
            commands.append((start, pending))
            pending = ""
    assert not pending, f"a continued line ends the block: {pending}"
    return commands


def steps(path: Path, text: str | None = None, python: bool = False) -> list[Step]:
    """The examples of one Markdown page (or of ``text``, a part of it), in order."""
    text = path.read_text(encoding="utf-8") if text is None else text
    files = {m.end(): m.group(1) for m in FILE_MARK.finditer(text)}
    found: list[Step] = []
    for block in BLOCK.finditer(text):
        indent, language = len(block.group(1)), block.group(2)
        body = "".join(line[indent:] for line in block.group(3).splitlines(keepends=True))
        line = text[:block.start()].count("\n") + 1  # the fence's line; the body starts on the next
        where = f"{path.name}:{line}"
        if block.start(3) in files:
            found.append(Step("file", body, where, files[block.start(3)]))
        elif language == "sh":
            found += [Step("run", command, f"{path.name}:{line + 1 + i}") for i, command in _commands(body)]
        elif language == "text":
            lines = body.splitlines()
            for i, text_line in enumerate(lines):
                if text_line.startswith("$ "):
                    output = lines[i + 1] if i + 1 < len(lines) else ""
                    found.append(Step("refuse" if output.startswith("error:") else "run", text_line[2:],
                                      f"{path.name}:{line + 1 + i}"))
        elif language == "python" and python:
            found.append(Step("python", body, where))
        elif language == "":
            commands = [code for code in body.splitlines() if re.match(r"\s*(\$ |shc |\.venv/)", code)]
            assert not commands, f"{where}: an unlabelled block holds commands (label it sh or text): {commands[0]}"
    return found


def exemption(command: str) -> str | None:
    """Why ``command`` is not run, or None."""
    return next((why for prefix, why in EXEMPT.items() if command.lstrip().startswith(prefix)), None)


def script(examples: list[Step]) -> str:
    """A bash script that runs the steps in order and stops at the first that fails, naming it."""
    lines = ["set -o pipefail", "fail() { echo \"FAILED at $1 (exit $2)\" >&2; exit 1; }"]
    for number, step in enumerate(examples):
        first = step.text.splitlines()[0] if step.text.strip() else ""
        lines.append(f"echo {shlex.quote(f'+ {step.where}: {first}')} >&2")
        if step.kind == "file":
            lines += [f"mkdir -p \"$(dirname {shlex.quote(step.name)})\"",
                      f"cat > {shlex.quote(step.name)} <<'SHC_DOCS_EOF'", step.text.rstrip("\n"), "SHC_DOCS_EOF"]
            continue
        if step.kind == "python":
            uncut = f"env -u {MAX_DURATION_ENV} " if step.where.split(":")[0] in UNCUT else ""
            lines += [f"cat > .docs_example_{number}.py <<'SHC_DOCS_EOF'", step.text.rstrip("\n"), "SHC_DOCS_EOF",
                      f"{uncut}python .docs_example_{number}.py"]
        elif (why := exemption(step.text)) is not None:
            lines.append(f"echo {shlex.quote(f'  skipped: {why}')} >&2")
            continue
        else:
            lines.append(step.text)
        expected = 2 if step.kind == "refuse" else 0
        lines.append(f"rc=$?; [ $rc -eq {expected} ] || fail {shlex.quote(step.where)} $rc")
    return "\n".join(lines) + "\n"


def clone(tmp_path: Path) -> Path:
    """A fresh clone of this repository (its committed state) in ``tmp_path``."""
    target = tmp_path / "clone"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(target)], check=True, timeout=120)
    return target


def run_script(examples: list[Step], where: Path, path_first: str | None, timeout: float) -> None:
    env = {**os.environ, MAX_DURATION_ENV: f"{MAX_DURATION_S:g}", "MPLBACKEND": "Agg"}
    env.pop("VIRTUAL_ENV", None)
    if path_first is not None:
        env["PATH"] = f"{path_first}{os.pathsep}{env.get('PATH', '')}"
    done = subprocess.run(["bash", "-c", script(examples)], cwd=where, env=env, capture_output=True, text=True,
                          timeout=timeout)
    assert done.returncode == 0, f"exit {done.returncode}\n{done.stdout[-3000:]}\n{done.stderr[-5000:]}"


def readme_sections() -> dict[str, str]:
    """The README's ``## `` sections by title."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return {part.split("\n", 1)[0].strip(): part for part in text.split("\n## ")[1:]}


def doc_pages() -> list[Path]:
    return sorted(p for p in (ROOT / "docs").rglob("*.md") if steps(p, python=False))


RUNNABLE_PYTHON = {"README.md", *UNCUT}
"""Pages whose ``python`` blocks are programs to run (elsewhere they are excerpts)."""


def reading_order() -> list[Path]:
    """Every page with examples in the order a reader meets them: the README, then ``docs/index.md``'s links in
    their order, then any page it does not link (sorted)."""
    linked = [ROOT / "docs" / name for name in re.findall(r"\]\(([\w/.-]+\.md)", (ROOT / "docs" / "index.md").read_text(
        encoding="utf-8"))]
    pages = [ROOT / "README.md", *dict.fromkeys(page for page in linked if page.is_file())]
    return pages + [page for page in doc_pages() if page not in pages]


def page_steps(page: Path) -> list[Step]:
    """A page's examples as :func:`reading_order` runs them (the README: its first five minutes)."""
    if page.name == "README.md":
        return steps(page, readme_sections()["First five minutes"], python=True)
    return steps(page, python=page.name in RUNNABLE_PYTHON)


OUT = re.compile(r"""(?:--out[= ]+|\bout=["'])([^\s"')]+)""")
"""An output path given on a command line (``--out DIR``) or to the Python API (``out="DIR"``)."""


def written(step: Step, files: dict[str, str]) -> list[str]:
    """The outputs a step writes: its ``--out``/``out=`` paths, or a sweep's or study's default ``runs/<name>``
    (``name`` from the file, a page's ``<!-- file: -->`` in ``files`` or the repository's)."""
    found = [m.group(1).rstrip("/") for m in OUT.finditer(step.text)]
    default = re.match(r"\s*(?:\$ )?shc (?:sweep|optimize) (\S+)", step.text)
    if not found and default is not None:
        name = default.group(1)
        text = files.get(name) or ((ROOT / name).read_text(encoding="utf-8") if (ROOT / name).is_file() else "")
        found.append(f"runs/{(tomllib.loads(text) if text else {}).get('name') or Path(name).stem}")
    return found


def collisions(pages: list[Path]) -> list[str]:
    """Where a page's example writes an output an earlier example (this page's or an earlier page's) already wrote,
    without replacing it (``--overwrite``, ``overwrite=True``): run in one clone, in order, it would stop at
    "already exists"."""
    first: dict[str, str] = {}
    files: dict[str, str] = {}
    found = []
    for page in pages:
        for step in page_steps(page):
            if step.kind == "file":
                files[step.name] = step.text
                continue
            replaces = "--overwrite" in step.text or "overwrite=True" in step.text or "--resume" in step.text
            for out in written(step, files):
                if out in first and not replaces and exemption(step.text) is None:
                    found.append(f"{step.where}: {out} is already written by {first[out]}")
                first.setdefault(out, step.where)
    return found


needs_git = pytest.mark.skipif(shutil.which("git") is None or not (ROOT / ".git").exists(),
                               reason="needs git and a git checkout to clone")


def test_examples_are_found_and_every_exemption_is_used() -> None:
    sections = readme_sections()
    first = steps(ROOT / "README.md", sections["First five minutes"], python=True)
    assert [s.kind for s in first].count("python") == 1 and len(first) >= 5
    assert first[0].text.startswith(". .venv/bin/activate")
    # every other shell block of the README is a set-up line, which tests/test_readme_setup.py runs
    others = [s for title, part in sections.items() if title != "First five minutes"
              for s in steps(ROOT / "README.md", part)]
    assert all("python3 -m pip install -q uv" in s.text for s in others), others
    every = [s for page in doc_pages() for s in steps(page)]
    assert len(every) > 40
    for prefix in EXEMPT:
        assert any(s.text.startswith(prefix) for s in every + first), f"exemption {prefix!r} is not used"
    assert not any("shared/" in s.text for s in every), "the docs may name only files of the repository"


def test_a_refusal_must_exit_2_and_a_failure_names_its_line(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text("<!-- file: a.txt -->\n```toml\nx = 1\n```\n\n```sh\ntest -f a.txt   # the file is there\n"
                    "true \\\n  --and-more\n```\n\n```text\n$ (exit 2)\nerror: refused\n$ false\n```\n",
                    encoding="utf-8")
    found = steps(page)
    assert [s.kind for s in found] == ["file", "run", "run", "refuse", "run"]
    with pytest.raises(AssertionError, match=r"FAILED at page.md:15 \(exit 1\)"):
        run_script(found, tmp_path, None, timeout=60)
    run_script(found[:-1], tmp_path, None, timeout=60)


@needs_git
def test_readme_first_five_minutes_run_after_the_readme_set_up_in_a_fresh_clone(tmp_path: Path) -> None:
    """Issue 26's acceptance: the set-up command, then the tour lines as written (shortened runs)."""
    where = clone(tmp_path)
    set_up, _ = setup_commands((ROOT / "README.md").read_text(encoding="utf-8"))
    first = steps(ROOT / "README.md", readme_sections()["First five minutes"], python=True)
    run_script([Step("run", set_up, "README.md: Set-up"), *first], where, None, timeout=900)
    assert (where / "runs" / "walk" / "summary.json").is_file()
    assert (where / "runs" / "readme-api-walk" / "summary.json").is_file()


def test_every_page_reads_in_order_and_no_page_writes_over_another_pages_outputs() -> None:
    """Issue 42 point 12: the README and docs/python-api.md both wrote ``runs/api-walk`` (the second stopped at
    "already exists"); tutorial §3 wrote the README's ``runs/arc``."""
    order = reading_order()
    assert order[:3] == [ROOT / "README.md", ROOT / "docs" / "tutorial.md", ROOT / "docs" / "robot-files.md"]
    assert len(set(order)) == len(order) and set(doc_pages()) <= set(order) and ROOT / "docs" / "python-api.md" in order
    assert collisions(order) == []


def test_a_collision_is_found(tmp_path: Path) -> None:
    first, second = tmp_path / "a.md", tmp_path / "b.md"
    first.write_text("```sh\nshc plan --out runs/x\nshc sweep sweeps/ci_smoke.toml\n```\n", encoding="utf-8")
    second.write_text("```sh\nshc simulate --out=runs/x --no-plots\nshc plan --out runs/x --overwrite\n"
                      "shc sweep sweeps/ci_smoke.toml --resume\nshc sweep other.toml\n```\n\n"
                      "<!-- file: other.toml -->\n```toml\nname = \"ci_smoke\"\n```\n\n"
                      "```sh\nshc sweep other.toml\n```\n", encoding="utf-8")
    assert collisions([first, second]) == ["b.md:2: runs/x is already written by a.md:2",
                                           "b.md:14: runs/ci_smoke is already written by a.md:3"]


@needs_git
@pytest.mark.slow
def test_every_page_runs_after_every_earlier_page_in_one_clone(tmp_path: Path) -> None:
    """The README and every page of docs/, in reading order, in one fresh clone (issue 42's acceptance): a page may
    neither depend on nor be stopped by what an earlier page left behind (the papers' experiments are most of its
    time); :func:`test_every_page_reads_in_order_and_no_page_writes_over_another_pages_outputs`
    is its fast check of the outputs."""
    where = clone(tmp_path)
    if sys.prefix != sys.base_prefix:
        (where / ".venv").symlink_to(sys.prefix, target_is_directory=True)
    examples = [step for page in reading_order() for step in page_steps(page)]
    run_script(examples, where, str(Path(sys.executable).parent), timeout=6 * 3600)
