"""``shc schema``: the JSON Schema of robot files, gait files or a run's ``summary.json``."""

from __future__ import annotations

import json
from typing import Any

import typer

from shc_cli.errors import NotFoundError


def print_schema(kind: str) -> None:
    """Print the JSON Schema of ``kind``: ``robot``, ``gait`` or ``summary``."""
    from shc_cli.record.summary import summary_schema
    from shc_cli.spec.gait import Gait
    from shc_cli.spec.loading import robot_file_schema

    document: dict[str, Any]
    if kind == "robot":
        document = robot_file_schema()
    elif kind == "gait":
        document = Gait.model_json_schema()
    elif kind == "summary":
        document = summary_schema()
    else:
        raise NotFoundError(f"schema: unknown kind '{kind}' (use 'robot', 'gait' or 'summary')")
    typer.echo(json.dumps(document, indent=2))
