"""``shc import``: OpenSHC parameter files and a legged robot's URDF or xacro as shc files."""

from __future__ import annotations

import math
from pathlib import Path

import typer

from shc_cli.errors import Issue, SpecError


def import_openshc(robot: Path, gait: Path | None, auto_pose: Path | None, out: Path, urdf: Path | None = None,
                   overwrite: bool = False) -> None:
    """OpenSHC YAML parameter files → shc robot, gait and auto-pose TOML files under ``out`` (masses from the
    ``urdf`` URDF/xacro)."""
    from shc_cli.interop.openshc import import_openshc as convert
    from shc_cli.outputs import refuse_file_like

    refuse_file_like(out, "robots/, gaits/ and poses/", out.with_suffix(""))
    for path in convert(robot, gait, auto_pose, out, urdf, overwrite):
        typer.echo(f"wrote {path}")


def import_urdf(file: Path, out: Path | None, name: str | None, legs: str, tip: list[str] | None,
                clearance: float | None, reach: float | None, snap: float, arguments: list[str] | None,
                forward: str | None = None, base: str | None = None, overwrite: bool = False) -> None:
    """A URDF or xacro → an shc robot file with its servo map; ``arguments`` are xacro's ``NAME=VALUE``, ``forward``
    the base_link axis the robot walks along (``+x``, ``+y``, ``-x``, ``-y``; None: the import decides), ``base`` the
    body link that is shc's base_link (None: the import decides)."""
    from shc_cli.interop.urdf_import import import_urdf as convert
    from shc_cli.outputs import refuse_file_like

    if out is not None:
        refuse_file_like(out, "robots/NAME.toml (NAME: --name or the URDF's robot name)", out.parent)
    if _is_mjcf(file):  # the file says which it is: an MJCF given to import urdf is imported as MJCF
        typer.echo(f"note: {file.name} is MJCF (a <mujoco> file): imported as shc import mjcf does")
        import_mjcf(file, out, name, legs, tip, clearance, reach, snap, forward, base, overwrite)
        return
    mappings = {}
    for item in arguments or []:
        key, sep, value = item.partition("=")
        if not sep:
            raise SpecError([Issue(None, None, "--arg", f"'{item}' is not NAME=VALUE", "e.g. --arg prefix=robot_")])
        mappings[key] = value
    turns = {"+x": 0.0, "+y": math.pi / 2, "-x": math.pi, "-y": -math.pi / 2}
    if forward is not None and forward not in turns:
        raise SpecError([Issue(None, None, "--forward", f"'{forward}' is not an axis", "give +x, +y, -x or -y")])
    result = convert(file, out, name, legs, tip, clearance, reach, snap, mappings,
                     None if forward is None else turns[forward], base, overwrite=overwrite)
    for note in result.notes:
        typer.echo(f"note: {note}")
    typer.echo(f"forward kinematics: largest tip difference to the URDF {result.fk_error:.2g} m at 200 random joint "
               "vectors per leg" + (f" ({result.fk_error_unsnapped:.2g} m to the URDF before snapping rpy values, "
                                    f"largest snap {result.snap:.2g} rad)" if result.snap > 0 else ""))
    if result.pose_path is not None:
        typer.echo(f"wrote {result.pose_path}")
    typer.echo(f"wrote {result.robot_path}")


def _is_mjcf(file: Path) -> bool:
    """Whether ``file``'s first element is ``<mujoco>`` (an MJCF file, whatever its name)."""
    import re

    if not file.is_file():
        return False
    with file.open("rb") as handle:
        head = handle.read(4096).decode("utf-8", errors="replace")
    head = re.sub(r"<\?.*?\?>|<!--.*?-->", "", head, flags=re.DOTALL)
    return re.match(r"\s*<mujoco[\s>/]", head) is not None


def import_mjcf(file: Path, out: Path | None, name: str | None, legs: str, tip: list[str] | None,
                clearance: float | None, reach: float | None, snap: float, forward: str | None = None,
                base: str | None = None, overwrite: bool = False) -> None:
    """An MJCF file → an shc robot file with its servo map (MuJoCo's loader; the URDF import's rules)."""
    from shc_cli.interop.mjcf_import import import_mjcf as convert
    from shc_cli.outputs import refuse_file_like

    if out is not None:
        refuse_file_like(out, "robots/NAME.toml (NAME: --name or the MJCF's model name)", out.parent)
    turns = {"+x": 0.0, "+y": math.pi / 2, "-x": math.pi, "-y": -math.pi / 2}
    if forward is not None and forward not in turns:
        raise SpecError([Issue(None, None, "--forward", f"'{forward}' is not an axis", "give +x, +y, -x or -y")])
    result, mujoco_error, notes = convert(file, out, name, legs, tip, clearance, reach, snap,
                                          None if forward is None else turns[forward], base, overwrite=overwrite)
    for note in [*notes, *result.notes]:
        typer.echo(f"note: {note}")
    typer.echo(f"forward kinematics: largest tip difference to MuJoCo's (mj_kinematics) {mujoco_error:.2g} m at 200 "
               "random joint vectors")
    if result.pose_path is not None:
        typer.echo(f"wrote {result.pose_path}")
    typer.echo(f"wrote {result.robot_path}")
