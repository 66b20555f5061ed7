"""A small TOML writer for what shc prints and writes (tables, numbers, text, lists)."""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import TypeGuard


def _value(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):
        items = [(k, v) for k, v in value.items() if v is not None]
        return "{ " + ", ".join(f"{_key(k)} = {_value(v)}" for k, v in items) + " }"
    if value is None:
        raise ValueError("TOML has no null")
    raise TypeError(f"cannot write {type(value).__name__} as TOML")


def _key(key: str) -> str:
    bare = key.replace("_", "").replace("-", "").isalnum()
    return key if bare else json.dumps(key)


def dump_toml(data: Mapping[str, object], _prefix: str = "") -> str:
    """TOML text of ``data``; ``None`` values are left out, small tables are written inline."""
    scalars = [(k, v) for k, v in data.items() if v is not None and not _is_table(v)]
    tables = [(k, v) for k, v in data.items() if _is_table(v)]
    lines = [f"{_key(k)} = {_value(v)}" for k, v in scalars]
    for key, table in tables:
        name = f"{_prefix}{_key(key)}"
        body = dump_toml(table, f"{name}.")
        has_scalars = any(not _is_table(v) and v is not None for v in table.values())
        if has_scalars:
            if lines or _prefix:
                lines.append("")
            lines.append(f"[{name}]")
        lines.append(body)
    return "\n".join(line for line in lines).rstrip() + ("\n" if not _prefix else "")


def _is_table(value: object) -> TypeGuard[dict[str, object]]:
    """Tables of tables (e.g. legs, joints) get headers; flat tables of scalars are written inline."""
    return isinstance(value, dict) and any(isinstance(v, dict) for v in value.values())
