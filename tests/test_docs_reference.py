"""The reference pages generated from the code are the code's current output (they cannot drift)."""

from __future__ import annotations

import importlib.util
import re
from types import ModuleType

import pytest

from .conftest import ROOT


def _generator() -> ModuleType:
    spec = importlib.util.spec_from_file_location("run_outputs", ROOT / "docs" / "run_outputs.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_run_outputs_page_is_what_the_table_writers_give() -> None:
    committed = (ROOT / "docs" / "run-outputs.md").read_text(encoding="utf-8")
    assert committed == _generator().page(), "regenerate: .venv/bin/python docs/run_outputs.py > docs/run-outputs.md"


def test_a_column_without_a_meaning_stops_the_generator() -> None:
    generator = _generator()
    with pytest.raises(SystemExit, match="'new_column' has no meaning"):
        generator.table_rows(["cycle", "new_column"])
    assert generator.patterns(["AR_coxa_cmd", "BL_coxa_cmd", "AR_force"], ["AR", "BL"], ["coxa"]) == [
        "<LEG>_<joint>_cmd", "<LEG>_force"]


def test_every_link_and_named_file_of_the_docs_exists() -> None:
    """Markdown links and backticked repository paths (``docs/x.md``, ``golden/...``) on every page point at files
    of the repository (a user's clone has nothing else)."""
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    missing = []
    for page in pages:
        text = page.read_text(encoding="utf-8")
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", text):
            if "://" not in target and not (page.parent / target).exists():
                missing.append(f"{page.relative_to(ROOT)}: link {target}")
        for named in re.findall(r"`((?:docs|golden|robots|gaits|sweeps|studies|benchmarks)/[\w./-]+\.\w+)`", text):
            if not (ROOT / named).exists():
                missing.append(f"{page.relative_to(ROOT)}: {named}")
    assert not missing, "\n".join(missing)


def test_install_hints_name_the_clone_install_and_extras_that_exist() -> None:
    """A missing dependency's message says the install that works from a clone (uv's venv has no pip, and `shc` on
    the package index is another project), and every extra it names is in pyproject.toml."""
    import tomllib

    from shc_cli.errors import install_hint

    extras = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["optional-dependencies"]
    named = {m for p in (ROOT / "shc_cli").rglob("*.py")
             for m in re.findall(r"install_hint\('(\w+)'\)", p.read_text(encoding="utf-8"))}
    assert named and named <= set(extras), named
    assert install_hint("dask").endswith("python3 -m uv pip install --python .venv -e '.[dask]'")
    assert install_hint().endswith("python3 -m uv pip install --python .venv -e .")
    assert "shc[" not in "".join(p.read_text(encoding="utf-8") for p in (ROOT / "shc_cli").rglob("*.py"))
