"""Reading a URDF or xacro file for ``shc import urdf``: xacro expanded without ROS, rpy snapped, parsed by yourdfpy.

``$(find PKG)`` has no ROS package index to ask here, so it is resolved from the file's own folders: the
nearest folder above the file (the file's own folder included) that is named ``PKG`` or holds a
``package.xml`` naming ``PKG``, or a folder ``PKG`` beside one of those folders (a ``src/`` of a catkin or
colcon workspace). A package found nowhere becomes ``package://PKG`` (ROS's own spelling): the import goes on,
and a note names the package and the elements that held it (a ros2_control parameter file is nothing
geometric); an include from it is refused with one line. An included file that does not exist under the
resolved path is looked for by name beside the file that includes it (a package's files copied flat into one
folder).

With ``--snap TOL``, angles in ``<origin rpy>`` within TOL of a multiple of π/2 are snapped to it before
parsing (``1.57`` meant as π/2), and so are joint axes within TOL of a frame axis (their small components go).
It moves the tips (by up to TOL × the leg's length), so ``shc import urdf`` snaps only when two axes meant to be
parallel are not quite (the common normal of nearly parallel axes is far away, and the DH offsets with it): on
its own only as far as :data:`shc_cli.interop.urdf_import.SNAP_STEPS` and ``SNAP_MOVE`` allow.
"""

from __future__ import annotations

import contextlib
import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from shc_cli.errors import Issue, SpecError

SUGGESTED_SNAP = 0.001
"""Smallest ``--snap`` suggested when axes are nearly parallel [rad] (1.57 is 0.0008 from π/2)."""


@dataclass(frozen=True)
class Source:
    """A URDF as read: the text after xacro, the text parsed (snapped), and the largest snap made.

    Attributes:
        path: the file given.
        text: URDF text after xacro expansion (capsules as cylinders), before snapping.
        snapped_text: the text parsed, rpy values snapped.
        snap: largest change made to an rpy value [rad].
    """

    path: Path
    text: str
    snapped_text: str
    snap: float
    warnings: tuple[str, ...] = ()
    """What could not be resolved and was left (a package of a ``$(find PKG)`` found nowhere)."""


def _fail(path: Path, problem: str, fix: str, line: int | None = None) -> SpecError:
    return SpecError([Issue(path, line, "", problem, fix)])


def find_package(name: str, start: Path) -> Path | None:
    """The folder of package ``name`` seen from the folder ``start`` (see the module docstring), or None."""
    for folder in [start, *start.parents]:
        if folder.name == name:
            return folder
        manifest = folder / "package.xml"
        if manifest.is_file() and re.search(rf"<name>\s*{re.escape(name)}\s*</name>", manifest.read_text("utf-8")):
            return folder
        if (folder / name).is_dir():
            return folder / name
    return None


@contextlib.contextmanager
def _xacro_hooks(path: Path, missing: dict[str, Path]) -> Iterator[None]:
    """Patch xacro's ``$(find)`` and include-path resolution for the duration of one expansion; packages found
    nowhere go to ``missing`` (``{name: folder searched from}``) and become ``package://NAME``."""
    import xacro
    import xacro.substitution_args as substitution

    def eval_find(package: str) -> str:
        current = Path(xacro.filestack[-1]) if xacro.filestack and xacro.filestack[-1] else path
        found = find_package(package, current.resolve().parent)
        if found is None:
            missing.setdefault(package, current.parent)
            return f"{MISSING}{package}"
        return str(found)

    original_find, original_abs = substitution._eval_find, xacro.abs_filename_spec

    def abs_filename_spec(spec: str) -> str:
        resolved: str = original_abs(spec)
        if not re.search("[*[?]+", resolved) and not Path(resolved).exists() and xacro.filestack:
            beside = Path(xacro.filestack[-1] or path).parent / Path(resolved).name
            if beside.exists():
                return str(beside)
        return resolved

    substitution._eval_find, xacro.abs_filename_spec = eval_find, abs_filename_spec
    try:
        yield
    finally:
        substitution._eval_find, xacro.abs_filename_spec = original_find, original_abs


MISSING = "package://"
"""What ``$(find PKG)`` of a package found nowhere becomes (``package://PKG``)."""


def _find_failure(path: Path, package: str, folder: Path) -> SpecError:
    return _fail(path, f"$(find {package}): no folder '{package}' (or package.xml naming it) above {folder}",
                 f"put the file inside the package's folder, named {package}")


def expand_xacro(path: Path, args: dict[str, str]) -> tuple[str, list[str]]:
    """The URDF text of a xacro file (``args``: xacro arguments ``name:=value``) and notes on packages found
    nowhere (module docstring)."""
    import xacro

    missing: dict[str, Path] = {}
    with _xacro_hooks(path, missing):
        try:
            document = xacro.process_file(str(path), mappings=dict(args))
        except SpecError:
            raise
        except Exception as error:  # xacro raises XacroException, ExpatError, NameError, ... with its own text
            cause = getattr(error, "exc", None)
            if isinstance(cause, SpecError):
                raise cause from None
            message = " ".join(str(error).split()) or type(error).__name__
            for package, folder in missing.items():
                if f"{MISSING}{package}" in message:  # an include from a package found nowhere
                    raise _find_failure(path, package, folder) from None
            raise _fail(path, f"xacro: {message}", "fix the xacro file, or give xacro arguments with --arg NAME=VALUE")\
                from None
    text: str = document.toprettyxml(indent="  ")
    return text, [_missing_note(document, package, folder) for package, folder in missing.items()]


def _missing_note(document: Any, package: str, folder: Path) -> str:
    """The note on a package found nowhere: which elements hold ``package://PKG`` (geometry or not)."""
    marker = f"{MISSING}{package}"
    holders: list[str] = []

    def visit(node: Any, parent: str) -> None:
        for child in node.childNodes:
            if child.nodeType == child.TEXT_NODE and marker in child.data:
                holders.append(parent)
            elif child.nodeType == child.ELEMENT_NODE:
                if any(marker in attribute.value for attribute in child.attributes.values()):
                    holders.append(child.tagName)
                visit(child, child.tagName)

    visit(document, "")
    places = ", ".join(f"<{tag}>" for tag in dict.fromkeys(holders)) or "nothing in the URDF"
    geometric = " (a mesh: the import reads one only for a tip on a knee axis)" if "mesh" in holders else ""
    return (f"$(find {package}): no folder '{package}' (or package.xml naming it) above {folder}: left as "
            f"{marker}, in {places}{geometric}")


def snap_rpy(text: str, tolerance: float) -> tuple[str, float]:
    """The URDF text with every ``origin rpy`` value within ``tolerance`` of a multiple of π/2 snapped to it, and
    every ``axis xyz`` component below ``tolerance`` of the axis' length set to 0.

    Returns the new text and the largest change [rad]."""
    root = ET.fromstring(text)  # also the well-formedness check: yourdfpy would recover from broken XML
    if tolerance <= 0.0:
        return text, 0.0
    largest = 0.0
    for origin in root.iter("origin"):
        rpy = origin.get("rpy")
        if rpy is None:
            continue
        values = [float(v) for v in rpy.split()]
        out = []
        for value in values:
            nearest = round(value / (math.pi / 2.0)) * (math.pi / 2.0)
            if 0.0 < abs(value - nearest) <= tolerance:
                largest = max(largest, abs(value - nearest))
                value = nearest
            out.append(repr(value))
        origin.set("rpy", " ".join(out))
    for axis in root.iter("axis"):  # a joint axis a hair off a frame axis: its small components go
        xyz = axis.get("xyz")
        if xyz is None:
            continue
        vector = [float(v) for v in xyz.split()]
        norm = math.sqrt(sum(v * v for v in vector))
        small = [abs(v) / norm for v in vector if 0.0 < abs(v) <= tolerance * norm] if norm > 0.0 else []
        if small and len(small) < len(vector):
            largest = max(largest, math.asin(min(math.sqrt(sum(v * v for v in small)), 1.0)))
            axis.set("xyz", " ".join(repr(0.0 if 0.0 < abs(v) <= tolerance * norm else v) for v in vector))
    return ET.tostring(root, encoding="unicode"), largest


def require() -> None:
    """Fail with one line if the optional dependencies of ``shc import urdf`` are missing."""
    import importlib.util

    from shc_cli.errors import BackendError, install_hint

    missing = [name for name in ("xacro", "yourdfpy") if importlib.util.find_spec(name) is None]
    if missing:
        raise BackendError(f"shc import urdf needs {' and '.join(missing)} ({install_hint()})")


def _known_geometry(text: str) -> str:
    """PyBullet's ``<capsule>`` (which ``shc export urdf`` writes) as a ``<cylinder>``: yourdfpy knows no capsule,
    and the import reads no geometry but foot spheres and the body's box."""
    if "<capsule" not in text:
        return text
    root = ET.fromstring(text)
    for geometry in root.iter("geometry"):
        for shape in geometry.findall("capsule"):
            shape.tag = "cylinder"
    return ET.tostring(root, encoding="unicode")


def read_source(path: Path, args: dict[str, str], snap: float, given: str | None = None) -> Source:
    """Read ``path`` (``.xacro`` expanded, anything else as URDF; ``given``: its URDF text, made from another
    format) and snap its rpy values.

    Raises:
        SpecError: missing file, xacro failure or malformed XML (one line).
    """
    require()
    if not path.is_file():
        raise _fail(path, "file not found", "check the path")
    warnings: list[str] = []
    if given is not None:
        text = given
    elif path.suffix == ".xacro" or ".xacro" in path.suffixes:
        text, warnings = expand_xacro(path, args)
    else:
        text = path.read_text(encoding="utf-8", errors="replace")
    try:
        text = _known_geometry(text)
        snapped, largest = snap_rpy(text, snap)
    except ET.ParseError as error:
        line = error.position[0] if hasattr(error, "position") else None
        raise _fail(path, f"malformed XML: {error}", "fix the XML (a URDF is one <robot> element)", line) from None
    except ValueError as error:
        raise _fail(path, f"an rpy value is not a number: {error}", "write three numbers, e.g. rpy=\"0 0 1.5708\"")\
            from None
    return Source(path, text, snapped, largest, tuple(warnings))


def parse_urdf(path: Path, text: str) -> Any:
    """yourdfpy's model of URDF ``text`` (no meshes loaded; the scene graph built for its forward kinematics)."""
    import io

    import yourdfpy
    from lxml import etree

    try:
        model = yourdfpy.URDF.load(io.BytesIO(text.encode("utf-8")), build_scene_graph=True, load_meshes=False,
                                   build_collision_scene_graph=False, load_collision_meshes=False)
    except etree.XMLSyntaxError as error:
        raise _fail(path, f"malformed XML: {error}", "fix the XML (a URDF is one <robot> element)") from None
    except (ValueError, LookupError, AttributeError, TypeError, ArithmeticError) as error:
        raise _fail(path, f"not a URDF yourdfpy can read: {error}", "check it with check_urdf or a URDF viewer")\
            from None
    return model
