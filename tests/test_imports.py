"""No import circles in ``shc_cli``: every module's imports (top-level and inside functions, not the
``TYPE_CHECKING`` ones) form a graph without cycles, so "open a run", the bag reader and the analysis build on each
other in one direction."""

from __future__ import annotations

import ast
from pathlib import Path

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


def import_graph() -> dict[str, set[str]]:
    """Module → the ``shc_cli`` modules it imports (a package's ``__init__`` counts as the package)."""
    files = {_module(path): path for path in PACKAGE.rglob("*.py")}
    graph: dict[str, set[str]] = {}
    for name, path in files.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        skip = _type_checking_lines(tree)
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
    assert {"shc_cli.loop.runread", "shc_cli.interop.bagrun"} <= graph["shc_cli.loop.opening"]
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
