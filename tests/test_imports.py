"""No import circles in ``shc_cli`` and every import pointing down the layers: every module's imports (top-level,
inside functions and the ``TYPE_CHECKING`` ones) form a graph without cycles, and each package has a layer of its
own, so the run record, the analysis, the bag reader and the run loop build on each other in one direction."""

from __future__ import annotations

import ast
import functools
from pathlib import Path
from typing import cast

import pytest

PACKAGE = Path(__file__).parents[1] / "shc_cli"


def _module(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _type_checking_lines(tree: ast.AST) -> set[int]:
    lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.body:
                lines.update(range(child.lineno, (child.end_lineno or child.lineno) + 1))
    return lines


@functools.cache  # parsed once per test process (≈ 0.7 s), not once per test that reads it
def import_graph(type_level: bool = True) -> dict[str, set[str]]:
    """Module → the ``shc_cli`` modules it imports (a package's ``__init__`` counts as the package); read-only.
    ``type_level``: with the imports under ``if TYPE_CHECKING:`` (a circle of type names is a circle too)."""
    files = {_module(path): path for path in PACKAGE.rglob("*.py")}
    graph: dict[str, set[str]] = {}
    for name, path in files.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        skip = set() if type_level else _type_checking_lines(tree)
        targets: set[str] = set()
        for node in ast.walk(tree):
            if getattr(node, "lineno", 0) in skip:
                continue
            if isinstance(node, ast.Import):
                targets.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                for alias in node.names:  # `from pkg import module` imports the module
                    full = f"{node.module}.{alias.name}"
                    targets.add(full if full in files else node.module)
        graph[name] = {t for t in targets if t in files and t != name}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in sorted(graph[node]):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def test_the_cycle_finder_finds_a_cycle() -> None:
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycles_in_shc_cli() -> None:
    graph = import_graph()
    assert {"shc_cli.record.runread", "shc_cli.interop.bagrun"} <= graph["shc_cli.domain.stored_run"]
    assert "shc_cli.domain.ros_config" in graph["shc_cli.domain.ros_session"]  # a TYPE_CHECKING import counts
    assert "shc_cli.domain.ros_config" not in import_graph(type_level=False)["shc_cli.domain.ros_session"]
    assert cycles(graph) == []


UPWARD = ("shc_cli.commands", "shc_cli.api", "shc_cli.cli")
"""What the domain layer must not import: the API facade, the commands and the CLI above it."""


def test_sweeps_and_optimize_import_nothing_above_the_domain() -> None:
    graph = import_graph()
    domain = {name: targets for name, targets in graph.items()
              if name.startswith(("shc_cli.domain.sweeps", "shc_cli.domain.optimize"))}
    assert "shc_cli.domain.optimize.loop" in domain and "shc_cli.domain.sweeps.pool" in domain
    upward = {name: {t for t in targets if t.startswith(UPWARD)} for name, targets in domain.items()}
    assert {name: targets for name, targets in upward.items() if targets} == {}


def test_the_api_imports_nothing_from_the_commands() -> None:
    """api.py is a facade over the domain: the commands print, the API returns results."""
    graph = import_graph()
    assert {"shc_cli.domain.sweeps.run", "shc_cli.domain.optimize.loop"} <= graph["shc_cli.api"]
    assert {t for t in graph["shc_cli.api"] if t.startswith(("shc_cli.commands", "shc_cli.cli"))} == set()


def test_sweep_and_optimize_commands_only_parse_call_and_print() -> None:
    for name in ("sweep", "optimize"):
        path = PACKAGE / "commands" / f"{name}.py"
        assert len(path.read_text(encoding="utf-8").splitlines()) <= 150, path
        assert import_graph()[f"shc_cli.commands.{name}"] <= {"shc_cli.api", "shc_cli.progress",
                                                               "shc_cli.domain.sweeps.results"}


LAYERS: dict[str, int] = {
    "shc_cli.spec": 0,
    "shc_cli.model": 1,
    "shc_cli.control": 2,
    "shc_cli.hardware": 3,
    "shc_cli.backends": 4,
    "shc_cli.hardware.emulator": 5, "shc_cli.hardware.emulator_protocol1": 5, "shc_cli.hardware.emulator_process": 5,
    "shc_cli.record": 6,
    "shc_cli.validation": 7,
    "shc_cli.analysis": 8,
    "shc_cli.plots": 9,
    "shc_cli.interop": 10,
    "shc_cli.loop": 11,
    "shc_cli.ros": 12,
    "shc_cli.ros2": 13,
    "shc_cli.live": 14,
    "shc_cli.replay": 15,
    "shc_cli.domain": 16,
    "shc_cli.gym": 17,
    "shc_cli.view": 18,
    "shc_cli.api": 19,
    "shc_cli": 20,
    "shc_cli.commands": 21,
    "shc_cli.cli": 22,
}
"""The layers, lowest first (a module may import its own package and the layers below; the longest prefix names a
module's layer): robot and gait files ← kinematics ← the controller ← servo buses ← backends (engines, servo
models, the Dynamixel backend) ← the emulated servo buses (they run the backends' servo physics; a package of
their own once the bus work settles) ← the run record (log format, readers, row kernels, summary models) ←
validation ← analysis ← plots ← interop (bags, OpenSHC files, URDF import) ← the run loop ← ROS 1 ← ROS 2 (a
transport beside ROS 1's, on its session) ← the live stream ← replay ← domain (runs, sweeps, optimize, opening a
stored run) ← the Gymnasium environment ← view ← api ← the package's lazy facade (``import shc_cli``) ← commands ←
cli."""
ANYWHERE = {"shc_cli.version", "shc_cli.errors", "shc_cli.events", "shc_cli.outputs", "shc_cli.progress"}
"""Helpers every layer may import: the version, the one exception tree, logging (events), file writing, the progress
bar."""
KNOWN_UPWARD: set[tuple[str, str]] = set()
"""Upward imports still to remove (each named, so no new one can creep in)."""


def layer(module: str) -> int:
    """The layer of a module (-1: a helper every layer may import)."""
    if module in ANYWHERE:
        return -1
    prefixes = [prefix for prefix in LAYERS  # "shc_cli" is the package's __init__ alone, not all of shc_cli
                if module == prefix or (prefix != "shc_cli" and module.startswith(prefix + "."))]
    if not prefixes:
        raise AssertionError(f"{module} is in no layer: add it to LAYERS")
    return LAYERS[max(prefixes, key=len)]


def test_every_layer_is_one_package_and_exists() -> None:
    """No two packages share a rank (a shared rank hid circles between them), and every entry names a module."""
    modules = set(import_graph())
    assert set(LAYERS) | ANYWHERE <= modules
    emulators = {name for name in LAYERS if name.startswith("shc_cli.hardware.emulator")}
    ranks = [rank for name, rank in LAYERS.items() if name not in emulators]
    assert len(ranks) == len(set(ranks))
    assert {LAYERS[name] for name in emulators} == {LAYERS["shc_cli.backends"] + 1}


def test_the_layer_rule_catches_an_upward_import() -> None:
    assert layer("shc_cli.spec.robot") < layer("shc_cli.control.controller") < layer("shc_cli.domain.simulate")
    assert layer("shc_cli.api") < layer("shc_cli.commands.simulate") < layer("shc_cli.cli")
    assert layer("shc_cli.record.runread") < layer("shc_cli.analysis.metrics") < layer("shc_cli.loop.physics_summary")
    assert layer("shc_cli.hardware.bus") < layer("shc_cli.backends.dynamixel") < layer("shc_cli.hardware.emulator")
    assert layer("shc_cli.errors") == -1 and layer("shc_cli") > layer("shc_cli.api")
    with pytest.raises(AssertionError, match="in no layer"):
        layer("shc_cli.new_package.module")


def test_nothing_imports_upward() -> None:
    """Every import (also inside functions and under ``TYPE_CHECKING``) points to the module's own layer or
    below."""
    upward = {(name, target) for name, targets in import_graph().items() for target in targets
              if layer(target) > layer(name)}
    assert upward - KNOWN_UPWARD == set()
    assert KNOWN_UPWARD - upward == set(), "fixed: remove it from KNOWN_UPWARD"


def test_every_command_module_is_short() -> None:
    """Commands only parse, call the API, print and choose the exit code: at most 150 lines each."""
    long = {path.name: n for path in (PACKAGE / "commands").glob("*.py")
            if (n := len(path.read_text(encoding="utf-8").splitlines())) > 150}
    assert long == {}


def _any_annotations(tree: ast.AST) -> list[int]:
    """Lines of annotations (parameters, returns, annotated names) that use ``Any``."""
    lines = []
    for node in ast.walk(tree):
        annotations: list[ast.expr | None] = []
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            arguments = node.args
            annotations = [a.annotation for a in [*arguments.posonlyargs, *arguments.args, *arguments.kwonlyargs,
                                                   *filter(None, (arguments.vararg, arguments.kwarg))]]
            annotations.append(node.returns)
        elif isinstance(node, ast.AnnAssign):
            annotations = [node.annotation]
        elif isinstance(node, ast.Assign) and isinstance(node.value, ast.Subscript):  # a type alias
            annotations = [node.value]
        for annotation in filter(None, annotations):
            if any((isinstance(n, ast.Name) and n.id == "Any") or (isinstance(n, ast.Constant) and n.value == "Any")
                   for n in ast.walk(annotation)):
                lines.append(cast(ast.stmt, node).lineno)
    return lines


def test_the_any_finder_finds_any() -> None:
    assert _any_annotations(ast.parse("def f(a: dict[str, Any]) -> None: ...\nX = Callable[[Any], None]")) == [1, 2]
    assert _any_annotations(ast.parse("def f(a: object) -> int: ...")) == []


def test_the_run_loop_boundaries_are_typed() -> None:
    """No ``Any`` in the Backend, Observer, Recorder and engine signatures."""
    found = {}
    for relative in ("backends/base.py", "backends/engine.py", "backends/engine_registry.py", "backends/simulated.py",
                     "backends/kinematic.py", "backends/dynamixel.py", "loop/run_loop.py"):
        lines = _any_annotations(ast.parse((PACKAGE / relative).read_text(encoding="utf-8")))
        if lines:
            found[relative] = lines
    assert found == {}
