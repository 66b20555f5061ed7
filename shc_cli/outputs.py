"""Writing outputs atomically: a file is either complete or absent, never half-written."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from shc_cli.errors import OutputError


def refuse_existing(paths: list[Path], overwrite: bool, option: str = "--out") -> None:
    """The one rule of every output: a file an shc command would write that already exists is refused before any
    work (one line: add --overwrite, or choose another ``option``), unless ``overwrite``. Run directories, sweeps and
    studies follow the same rule through :class:`shc_cli.record.runlog.RunDirectory` and ``clear_output``."""
    existing = [path for path in paths if path.exists()]
    if existing and not overwrite:
        what = "it" if len(existing) == 1 else f"it and {len(existing) - 1} more of the outputs"
        raise OutputError(f"{existing[0]}: already exists (add --overwrite to replace {what}, or choose another "
                          f"{option})")


FILE_SUFFIXES = frozenset({".mcap", ".db3", ".bag", ".toml", ".urdf", ".xacro", ".yaml", ".yml", ".json", ".csv",
                           ".png", ".mp4", ".gif", ".zip"})
"""Suffixes that make a path a file's name, not a folder's (``runs/arc.mcap``, ``X/robot.toml``)."""


def refuse_file_like(path: Path, holds: str, example: Path, option: str = "--out") -> None:
    """The other half of the output rule: an ``option`` that names a folder (one holding ``holds``) given a file's
    name (``runs/arc.mcap``, ``X/robot.toml``) is refused in one line before any work, instead of a folder of that
    name being made. ``example``: the folder to suggest."""
    if path.suffix.lower() in FILE_SUFFIXES:
        raise OutputError(f"{path}: {option} is the folder that will hold {holds}, and this names a file (ends in "
                          f"{path.suffix}); give a folder, e.g. {option} {example}")


def ensure_dir(path: Path) -> Path:
    """Create ``path`` (and parents); a one-line error if that is impossible."""
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise OutputError(f"{path}: cannot create output directory: {error.strerror} (choose another --out)") from None
    return path


@contextmanager
def atomic_path(path: Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; rename it to ``path`` only if the block succeeds."""
    ensure_dir(path.parent)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".partial" + path.suffix, dir=path.parent)
    os.close(handle)
    try:
        yield Path(temporary)
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(temporary, 0o666 & ~mask)  # mkstemp makes 0600; a finished output gets the usual permissions
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically."""
    with atomic_path(path) as temporary:
        temporary.write_text(text, encoding="utf-8")
