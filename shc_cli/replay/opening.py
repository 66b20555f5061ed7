"""Opening a replay source: a recording prefix, a ROS 1 bag file or a ROS 2 bag directory → :class:`Recorded`.

Above :mod:`~shc_cli.replay.source` (the shared data type) and its two readers, so they import in one direction.
"""

from __future__ import annotations

from pathlib import Path

from shc_cli.errors import NotFoundError
from shc_cli.replay.source import RECORDING_PARTS, Recorded


def recording_prefix(source: Path) -> Path | None:
    """``DIR/NAME`` if ``source`` is a recording prefix (or one of its CSV files), else ``None``."""
    text = str(source)
    for part in RECORDING_PARTS:
        suffix = f"_{part}.csv.gz"
        if text.endswith(suffix) and source.is_file():
            return Path(text[: -len(suffix)])
    if Path(f"{text}_joints.csv.gz").is_file():
        return source
    return None


def open_source(source: Path) -> Recorded:
    """Read a recording prefix, a ROS 1 bag file or a ROS 2 bag directory; one-line errors for anything else."""
    prefix = recording_prefix(source)
    if prefix is not None:
        from shc_cli.replay.recording import read_recording

        return read_recording(prefix)
    if (source.is_dir() and (source / "metadata.yaml").is_file()) or (source.is_file() and _is_ros1_bag(source)):
        from shc_cli.replay.bagfile import read_bag

        return read_bag(source)
    if source.is_dir() and (source / "summary.json").is_file():
        raise NotFoundError(f"{source}: an shc run, not an OpenSHC recording (replay compares shc with a recording of "
                            f"OpenSHC; to look at this run: shc view {source}, shc analyze {source})")
    if source.is_dir():
        raise NotFoundError(f"{source}: a directory without metadata.yaml is not a ROS 2 bag (give the bag's "
                            "directory, a ROS 1 .bag file or a recording prefix DIR/NAME)")
    if source.is_file():
        raise NotFoundError(f"{source}: not a ROS 1 bag (no '#ROSBAG' header) nor a recording CSV (give a ROS 1 "
                            ".bag file, a ROS 2 bag directory or a recording prefix DIR/NAME)")
    raise NotFoundError(f"{source}: no such bag, and no {source.name}_joints.csv.gz beside it (give a ROS 1 .bag "
                        "file, a ROS 2 bag directory or a recording prefix DIR/NAME)")


def _is_ros1_bag(path: Path) -> bool:
    with path.open("rb") as handle:
        return handle.read(8) == b"#ROSBAG "
