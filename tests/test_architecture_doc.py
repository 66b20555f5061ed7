"""docs/architecture.md against the code: every file, package and dotted name it gives exists, every class it
names is defined, and its picture of the layers is the order tests/test_imports.py enforces.

How the page names things (and this test reads them): paths relative to ``shc_cli/`` (``loop/run_loop.py``,
``record/``), a name in a module as ``path/module.Name`` or ``package.module.name`` (``record/runlog.LogRecorder``,
``validation.load_checked``), a class by its bare name (``RunLoop``).
"""

from __future__ import annotations

import ast
import functools
import importlib
import re

from .conftest import ROOT
from .test_imports import LAYERS

PAGE = ROOT / "docs" / "architecture.md"
PACKAGE = ROOT / "shc_cli"
PATH = re.compile(r"^[\w*]+(?:/[\w*]+)*(?:\.py|/)$")
DOTTED = re.compile(r"^(?:[a-z_][\w]*/)*[a-z_]\w*(?:\.[A-Za-z_]\w*)+$")
CLASS = re.compile(r"^[A-Z][a-z]\w*(?:\.[a-z_]\w*)?$")
NOT_CODE = {".csv", ".json", ".md", ".toml", ".partial", ".py"}


def _text(page: str) -> tuple[list[str], list[str]]:
    """The backticked tokens of the prose and the lines of the indented pictures."""
    prose: list[str] = []
    pictures: list[str] = []
    for line in page.splitlines():
        (pictures if line.startswith("    ") and not line.lstrip().startswith(("*", "`")) else prose).append(line)
    return re.findall(r"`([^`\n]+)`", "\n".join(prose)), pictures


def path_exists(token: str) -> bool:
    """A path relative to shc_cli/ or the repository (``*`` as a wildcard), or a bare file name in shc_cli/."""
    bases = (PACKAGE, ROOT)
    if "/" not in token.rstrip("/"):
        return any(any(base.glob(token)) for base in bases) or any(PACKAGE.rglob(token.rstrip("/")))
    return any(any(base.glob(token.rstrip("/"))) for base in bases)


@functools.cache
def _classes() -> dict[str, list[str]]:
    """Class (and type alias) name → the modules of shc_cli that define it."""
    found: dict[str, list[str]] = {}
    for path in PACKAGE.rglob("*.py"):
        module = ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            names = [node.name] if isinstance(node, ast.ClassDef) else [
                t.id for t in getattr(node, "targets", [getattr(node, "target", None)]) if isinstance(t, ast.Name)]
            for name in names:
                found.setdefault(name, []).append(module)
    return found


def resolve(token: str) -> bool:
    """Whether ``path/module.name.attr`` (or ``package.module.name``) names something in shc_cli."""
    parts = token.replace("/", ".").split(".")
    for cut in range(len(parts), 0, -1):
        module = "shc_cli." + ".".join(parts[:cut])
        try:
            value: object = importlib.import_module(module)
        except ModuleNotFoundError:
            continue
        for attribute in parts[cut:]:
            if not hasattr(value, attribute):
                return False
            value = getattr(value, attribute)
        return True
    return False


def class_exists(token: str) -> bool:
    name, _, attribute = token.partition(".")
    for module in _classes().get(name, []):
        value = getattr(importlib.import_module(module), name)
        if not attribute or hasattr(value, attribute):
            return True
    return False


def test_the_checks_tell_a_missing_name_from_a_present_one() -> None:
    assert path_exists("loop/run_loop.py") and path_exists("record/") and path_exists("hardware/emulator*.py")
    assert not path_exists("runs/loop.py") and not path_exists("planning.py") and not path_exists("runs/")
    assert resolve("record/runlog.LogRecorder") and resolve("validation.load_checked")
    assert not resolve("runs/loop.SequenceInput") and not resolve("domain/hardware._source")
    assert not resolve("backends/engine.ENGINES")  # the names live in engine_registry
    assert class_exists("RunLoop") and class_exists("Controller.step") and not class_exists("Controller.fly")


def test_every_path_and_name_the_page_gives_exists() -> None:
    tokens, pictures = _text(PAGE.read_text(encoding="utf-8"))
    missing = []
    for token in tokens:
        if PATH.match(token):
            ok = path_exists(token)
        elif DOTTED.match(token) and not token.endswith(tuple(NOT_CODE)) and "." in token:
            ok = resolve(token)
        elif CLASS.match(token) and token not in {"None", "True", "False"}:
            ok = class_exists(token)
        else:
            continue
        if not ok:
            missing.append(token)
    for line in pictures:
        missing += [word for word in re.findall(r"[\w*]+(?:/[\w*]+)*(?:\.py|/)(?=[\s,:;)]|$)", line)
                    if not path_exists(word)]
    assert missing == []


def _layer_picture() -> list[str]:
    section = PAGE.read_text(encoding="utf-8").split("## The layers", 1)[1].split("\n## ", 1)[0]
    return [line.split()[0].rstrip(",") for line in section.splitlines() if line.startswith("    ")]


MODULE_OF = {"__init__.py": "shc_cli", "hardware/emulator*.py": "shc_cli.hardware.emulator"}


def test_the_layer_picture_is_the_enforced_order() -> None:
    entries = _layer_picture()[:-1]  # the last line: the helpers every layer may import
    modules = [MODULE_OF.get(entry, "shc_cli." + entry.removesuffix(".py").removesuffix("/").replace("/", "."))
               for entry in entries]
    assert all(module in LAYERS for module in modules), modules
    ranks = [LAYERS[module] for module in modules]
    assert ranks == sorted(set(LAYERS.values()), reverse=True)  # top first, every layer once
