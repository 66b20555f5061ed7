"""Loading robot and gait files: ``extends``, leg templates and mirrors, then validation.

The order is: read the file and every file it ``extends`` (child values override parent values,
tables merge), expand each leg (``template = "name"`` merges a ``[templates.name]`` table under
the leg's own keys; ``mirror = "AR"`` copies the expanded AR leg reflected through the body's
x–z plane), then validate the result with the pydantic models. Every value keeps its origin, so
errors name the line the user wrote even when the value reached the leg through a template.
"""

from __future__ import annotations

import difflib
import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError
from pydantic_core import ErrorDetails

from shc_cli.errors import Issue, NotFoundError, SpecError
from shc_cli.spec.gait import Gait
from shc_cli.spec.robot import DH, Joint, Leg, Robot
from shc_cli.spec.source import Document, KeyPath, Origin, Sourced, deep_merge, origins, unwrap

ModelT = TypeVar("ModelT", bound=BaseModel)

FILE_KEYS = ("extends", "templates", "mirror")
DH_ANGLES = ("theta", "alpha")


def data_dir(kind: str) -> Path:
    """Folder of the bundled ``robots`` or ``gaits`` (installed wheel or source checkout)."""
    installed = Path(__file__).resolve().parents[1] / "data" / kind
    if installed.is_dir():
        return installed
    return Path(__file__).resolve().parents[2] / kind


def bundled(kind: str) -> list[str]:
    """Names of the bundled files of a kind, sorted."""
    folder = data_dir(kind)
    return sorted(p.stem for p in folder.glob("*.toml")) if folder.is_dir() else []


def resolve(kind: str, name_or_path: str | Path, relative_to: Path | None = None) -> Path:
    """Find a robot or gait file by path, or by bundled name (``bullet``, ``tripod``)."""
    text = str(name_or_path)
    candidates = [Path(text)]
    if relative_to is not None:
        candidates.insert(0, relative_to / text)
    for candidate in candidates:
        if candidate.is_file():
            return candidate
    stem = Path(text).stem if text.endswith(".toml") else text
    named = data_dir(kind) / f"{stem}.toml"
    noun = kind.rstrip("s")
    if text.endswith(".toml") or "/" in text or "\\" in text:  # a path: never silently the bundled file instead
        where = f" (looked in {Path.cwd()}{f' and {relative_to}' if relative_to is not None else ''})"
        if named.is_file():
            raise NotFoundError(f"{text}: no such {noun} file{where}; the bundled {noun} of that name is "
                                f"given without a path: '{stem}'")
    elif named.is_file():
        return named
    names = bundled(kind)
    close = difflib.get_close_matches(stem, names, n=1)
    hint = f"did you mean '{close[0]}'? " if close else ""
    raise NotFoundError(
        f"{text}: no such {noun} file or bundled {noun} ({hint}bundled: {', '.join(names) or 'none'})"
    )


@dataclass
class Located:
    """A validated model plus a way to find the file and line behind any of its fields."""

    path: Path
    origin_map: dict[KeyPath, Origin]
    documents: dict[Path, Document] = field(default_factory=dict)

    def where(self, loc: KeyPath) -> tuple[Path, int | None]:
        """File and line that set the field at ``loc``.

        In order: the value's own origin; the key as written in the loaded file itself (a table, or a
        value with nothing inside such as ``joints = {}``); the nearest written ancestor.
        """
        origin = self.origin_map.get(loc)
        if origin is None:
            own = self.documents.get(self.path)
            if own is not None and loc in own.lines:
                return self.path, own.lines[loc]
            origin = self._ancestor_origin(loc)
        if origin is None:
            return self.path, None
        document = self.documents.get(origin.file)
        return origin.file, document.line(origin.path) if document else None

    def _ancestor_origin(self, loc: KeyPath) -> Origin | None:
        for depth in range(len(loc), 0, -1):
            prefix = loc[:depth]
            below = [(k, o) for k, o in self.origin_map.items() if k[:depth] == prefix]
            if not below:
                continue
            same = [o for _, o in below if o.path[:depth] == prefix]
            pool = same or [o for _, o in below]
            # A value the loaded file wrote over its parent's is likelier the mistake than the parent's.
            chosen = next((o for o in pool if o.file == self.path), pool[0])
            return Origin(chosen.file, chosen.path[:depth])
        return None

    def issue(self, loc: KeyPath, problem: str, fix: str = "") -> Issue:
        file, line = self.where(loc)
        return Issue(file, line, ".".join(str(p) for p in loc), problem, fix)


@dataclass
class LoadedRobot(Located):
    """A robot file, loaded: the robot and where each of its fields was written."""

    robot: Robot = field(kw_only=True)
    mirrors: dict[str, tuple[str, set[str]]] = field(default_factory=dict)
    """Mirrored leg id → (source leg id, names of the joints whose angles are negated)."""


@dataclass
class LoadedGait(Located):
    """A gait file, loaded: the gait and where each of its fields was written."""

    gait: Gait = field(kw_only=True)


def _read_with_extends(path: Path, seen: tuple[Path, ...] = ()) -> tuple[dict[str, Any], dict[Path, Document]]:
    document = Document(path)
    if path.resolve() in seen:
        chain = " -> ".join(p.name for p in (*seen, path.resolve()))
        raise SpecError([Issue(path, document.line(("extends",)), "extends", f"circular extends: {chain}",
                               "remove one of the extends")])
    data = document.sourced()
    documents = {path: document}
    parent_ref = data.pop("extends", None)
    if parent_ref is None:
        return data, documents
    if not isinstance(parent_ref.value, str):
        raise SpecError([Issue(path, document.line(("extends",)), "extends",
                               "must be a robot name or a path (a string)", 'e.g. extends = "bullet"')])
    try:
        parent_path = resolve("robots", parent_ref.value, relative_to=path.parent)
    except NotFoundError as error:
        raise SpecError([Issue(path, document.line(("extends",)), "extends", str(error), "")]) from None
    parent, parent_docs = _read_with_extends(parent_path, (*seen, path.resolve()))
    return deep_merge(parent, data), {**parent_docs, **documents}


def _negate(leaf: Any) -> Any:
    if not isinstance(leaf, Sourced):
        return leaf
    value = leaf.value
    if isinstance(value, bool) or not isinstance(value, (int, float, list)):
        return leaf
    if isinstance(value, list):
        return Sourced([0.0 - v if isinstance(v, (int, float)) and not isinstance(v, bool) else v for v in value],
                       leaf.origin)
    return Sourced(0.0 - value, leaf.origin)


def _mirror_rules(data: dict[str, Any], leg: dict[str, Any]) -> tuple[set[tuple[str, str]], set[str]]:
    """(DH angles to negate as (link, field), joints whose angles negate); default: a full reflection."""
    joints = [j for j in leg.get("joints", {}) if isinstance(leg["joints"], dict)]
    rules = unwrap(data.get("mirror", {}))
    if not rules:
        dh = {("base", a) for a in DH_ANGLES} | {(j, a) for j in joints for a in DH_ANGLES}
        return dh, set(joints)
    dh_rules = set()
    for item in rules.get("negate_dh", []):
        link, _, name = str(item).partition(".")
        dh_rules.add((link, name))
    return dh_rules, {str(j) for j in rules.get("negate_joints", [])}


def _unknown_mirror_names(data: dict[str, Any], leg: dict[str, Any]) -> tuple[str, str, str] | None:
    """(rule key, offending entry, valid names) for the first [mirror] entry naming nothing in ``leg``."""
    joints = list(leg.get("joints", {})) if isinstance(leg.get("joints"), dict) else []
    rules = unwrap(data.get("mirror", {}))
    if not isinstance(rules, dict):
        return None
    for item in rules.get("negate_dh", []) if isinstance(rules.get("negate_dh"), list) else []:
        link = str(item).partition(".")[0]
        if link != "base" and link not in joints:
            return "negate_dh", str(item), ", ".join(["base", *joints])
    for item in rules.get("negate_joints", []) if isinstance(rules.get("negate_joints"), list) else []:
        if str(item) not in joints:
            return "negate_joints", str(item), ", ".join(joints)
    return None


def _reflect(data: dict[str, Any], leg: dict[str, Any]) -> dict[str, Any]:
    """The leg reflected through the x–z plane of the body (left ↔ right)."""
    dh_rules, joint_rules = _mirror_rules(data, leg)
    out = deep_merge({}, leg)
    if isinstance(out.get("stance"), dict) and "y" in out["stance"]:
        out["stance"] = {**out["stance"], "y": _negate(out["stance"]["y"])}
    if isinstance(out.get("base"), dict):
        out["base"] = {k: _negate(v) if ("base", k) in dh_rules else v for k, v in out["base"].items()}
    joints = out.get("joints")
    if isinstance(joints, dict):
        new_joints = {}
        for name, joint in joints.items():
            if not isinstance(joint, dict):
                new_joints[name] = joint
                continue
            joint = {k: _negate(v) if (name, k) in dh_rules else v for k, v in joint.items()}
            if name in joint_rules:
                lo, hi = joint.get("min"), joint.get("max")
                if lo is not None:
                    joint["max"] = _negate(lo)
                if hi is not None:
                    joint["min"] = _negate(hi)
                for key in ("packed", "unpacked"):
                    if key in joint:
                        joint[key] = _negate(joint[key])
            new_joints[name] = joint
        out["joints"] = new_joints
    return out


def _expand_legs(
    data: dict[str, Any], documents: dict[Path, Document], mirrors: dict[str, tuple[str, set[str]]]
) -> dict[str, Any]:
    """Resolve ``template`` and ``mirror`` in every leg; record mirrors in ``mirrors``."""
    raw_legs = data.get("legs")
    if not isinstance(raw_legs, dict):
        return data
    templates = data.get("templates", {})
    expanded: dict[str, Any] = {}
    failed: set[str] = set()
    issues: list[Issue] = []

    def where(origin: Origin) -> int | None:
        doc = documents.get(origin.file)
        return doc.line(origin.path) if doc else None

    def expand(leg_id: str, stack: tuple[str, ...]) -> dict[str, Any] | None:
        """The expanded leg, or None if it cannot be built (its issue is reported once)."""
        if leg_id in expanded:
            return expanded[leg_id]  # type: ignore[no-any-return]
        if leg_id in failed:
            return None
        result = build(leg_id, stack)
        if result is None:
            failed.add(leg_id)
        else:
            expanded[leg_id] = result
        return result

    def build(leg_id: str, stack: tuple[str, ...]) -> dict[str, Any] | None:
        leg = raw_legs[leg_id]
        if not isinstance(leg, dict):
            return None
        own = {k: v for k, v in leg.items() if k not in ("template", "mirror")}
        template_ref, mirror_ref = leg.get("template"), leg.get("mirror")
        base: dict[str, Any] = {}
        if template_ref is not None and mirror_ref is not None:
            issues.append(Issue(template_ref.origin.file, where(template_ref.origin), f"legs.{leg_id}",
                                "a leg takes either template or mirror, not both", "keep one of them"))
            return None
        if template_ref is not None:
            name = template_ref.value
            if not isinstance(name, str) or not isinstance(templates.get(name), dict):
                close = difflib.get_close_matches(str(name), list(templates), n=1)
                fix = f"did you mean '{close[0]}'?" if close else f"templates defined: {', '.join(templates) or 'none'}"
                issues.append(Issue(template_ref.origin.file, where(template_ref.origin),
                                    f"legs.{leg_id}.template", f"no template named '{name}'", fix))
                return None
            base = templates[name]
        if mirror_ref is not None:
            name = mirror_ref.value
            if not isinstance(name, str) or name not in raw_legs or name == leg_id or name in stack:
                if name == leg_id:
                    problem, fix = "a leg cannot mirror itself", "name the leg it reflects on the other side"
                elif name in stack:
                    cycle = " -> ".join((*stack[stack.index(name):], leg_id, name))
                    problem, fix = f"mirror cycle: {cycle}", "give one of these legs a template instead"
                else:
                    close = difflib.get_close_matches(str(name), [k for k in raw_legs if k != leg_id], n=1)
                    problem = f"no leg named '{name}' to mirror"
                    fix = f"did you mean '{close[0]}'?" if close else f"legs: {', '.join(raw_legs)}"
                issues.append(Issue(mirror_ref.origin.file, where(mirror_ref.origin),
                                    f"legs.{leg_id}.mirror", problem, fix))
                return None
            source = expand(name, (*stack, leg_id))
            if source is None:
                return None
            unknown = _unknown_mirror_names(data, source)
            if unknown:
                path, item, known = unknown
                origin = data["mirror"][path].origin
                issue = Issue(origin.file, where(origin), f"mirror.{path}",
                              f"'{item}' names no link or joint of the legs it mirrors", f"use one of: {known}")
                if issue not in issues:
                    issues.append(issue)
                return None
            base = _reflect(data, source)
            mirrors[leg_id] = (name, _mirror_rules(data, source)[1])
        return deep_merge(base, own)

    legs_out = {}
    for leg_id in raw_legs:
        result = expand(leg_id, ())
        legs_out[leg_id] = result if result is not None else raw_legs[leg_id]
    if issues:
        raise SpecError(issues)
    return {**data, "legs": legs_out}


def _model_at(model: type[BaseModel], loc: KeyPath) -> type[BaseModel] | None:
    """The pydantic model class that owns the last element of ``loc`` (for did-you-mean)."""
    current: Any = model
    for part in loc[:-1]:
        if isinstance(part, int):  # a list index: list[Model] was already reduced to Model
            continue
        if isinstance(current, type) and issubclass(current, BaseModel):
            info = current.model_fields.get(str(part))
            current = info.annotation if info else None
        elif getattr(current, "__origin__", None) is dict:
            current = current.__args__[1]
        else:
            return None
        args = getattr(current, "__args__", None)
        if args and getattr(current, "__origin__", None) is not dict:
            models = [a for a in args if isinstance(a, type) and issubclass(a, BaseModel)]
            current = models[0] if models else current
    if getattr(current, "__origin__", None) is dict:
        return None
    return current if isinstance(current, type) and issubclass(current, BaseModel) else None


def _did_you_mean(model: type[BaseModel], loc: KeyPath) -> str | None:
    """The allowed key closest to the unknown key at ``loc`` (letter case ignored), if any is close."""
    owner = _model_at(model, loc)
    lowered = {name.lower(): name for name in (owner.model_fields if owner else [])}
    close = difflib.get_close_matches(str(loc[-1]).lower(), list(lowered), n=1, cutoff=0.6)
    return lowered[close[0]] if close else None


_UNIT_HINT = "write a plain number in SI units (m, rad, s, kg) without a unit"


def _describe(error: ErrorDetails, model: type[BaseModel]) -> tuple[str, str]:
    """(problem, fix) for one pydantic error, in words a robot builder understands."""
    kind, loc, given = error["type"], error["loc"], error.get("input")
    name = str(loc[-1]) if loc else ""
    if kind == "extra_forbidden":
        owner = _model_at(model, loc)
        allowed = list(owner.model_fields) if owner else []
        close = _did_you_mean(model, loc)
        fix = f"did you mean '{close}'?" if close else (f"allowed: {', '.join(allowed)}" if allowed else "remove it")
        return f"unknown key '{name}'", fix
    if kind == "missing":
        if loc and isinstance(loc[-1], int) and isinstance(given, list):  # an item of a fixed-length list
            return f"too few values ({len(given)} given)", "give one value per item, as 'shc schema robot' lists them"
        return "missing required field", f"add '{name} = ...'"
    if kind in ("float_parsing", "float_type", "int_parsing", "int_type", "int_from_float"):
        wanted = "a whole number" if kind.startswith("int") else "a number"
        plain = _UNIT_HINT if wanted == "a number" else "write an integer"
        if isinstance(given, str) and any(c.isalpha() for c in given):
            return f"expected {wanted}, got the text '{given}'", plain
        if isinstance(given, str):
            return f"expected {wanted}, got '{given}'", "remove the quotes"
        if isinstance(given, bool):
            return f"expected {wanted}, got {str(given).lower()}", f"write {wanted}, not true or false"
        return f"expected {wanted}, got {given!r}", plain
    if kind == "finite_number":
        return f"must be a finite number, got {given!r}", "replace nan/inf with a real value"
    if kind in ("bool_type", "bool_parsing"):
        return f"expected true or false, got {given!r}", "write true or false (lower case, no quotes)"
    if kind in ("string_type",):
        return f"expected text, got {given!r}", 'quote it, e.g. "tripod"'
    if kind == "literal_error":
        return f"{given!r} is not allowed", error["msg"].replace("Input should be", "use")
    if kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
        bound = next(iter(error.get("ctx", {}).values()), "")
        bound = f"{bound:g}" if isinstance(bound, float) else bound
        op = {"greater_than": ">", "greater_than_equal": "≥", "less_than": "<", "less_than_equal": "≤"}[kind]
        return f"must be {op} {bound}, got {given!r}", "change the value"
    if kind in ("dict_type", "model_type", "model_attributes_type"):
        return f"expected a table, got {given!r}", f"write it as a table: [{'.'.join(map(str, loc))}] or {{ ... }}"
    if kind in ("list_type", "tuple_type"):
        return f"expected a list, got {given!r}", "write it as [a, b, ...]"
    if kind in ("too_short", "too_long"):
        return error["msg"].lower().replace("tuple", "list"), "give the stated number of values"
    if kind == "value_error":
        message = str(error["msg"]).removeprefix("Value error, ")
        problem, _, fix = message.partition("; ")
        return problem, fix
    return str(error["msg"]), ""


def _validate(model: type[ModelT], data: dict[str, Any], located: Located,
              mirrors: Mapping[str, tuple[str, set[str]]] | None = None) -> ModelT:
    """``model`` from ``data``, or a SpecError with every mistake at its file and line (``mirrors``: a robot's
    mirrored legs, whose issues repeat their source leg's)."""
    try:
        return model.model_validate(data)
    except ValidationError as error:
        errors: list[ErrorDetails] = error.errors()
        # A misspelt required key is one mistake: its "did you mean" already names the missing field.
        suggested: set[KeyPath] = set()
        for item in errors:
            loc: KeyPath = tuple(item["loc"])
            close = _did_you_mean(model, loc) if item["type"] == "extra_forbidden" else None
            if close is not None:
                suggested.add((*loc[:-1], close))
        issues = []
        for item in errors:
            loc = tuple(item["loc"])
            if item["type"] == "missing" and loc in suggested:
                continue
            if item["type"] == "missing" and loc and isinstance(loc[-1], int):
                loc = loc[:-1]  # a short fixed-length list: one issue at the list, not one per absent item
            problem, fix = _describe(item, model)
            issues.append(located.issue(loc, problem, fix))
        raise SpecError(one_per_mistake(issues, mirrors or {})) from None


def one_per_mistake(issues: list[Issue], mirrors: Mapping[str, tuple[str, set[str]]]) -> list[Issue]:
    """Each written mistake once, though every leg that uses the value fails on it.

    A template's line fails in each leg built from the template, and a leg's values fail again in the
    legs that mirror it. Keep the first issue per file, line, field below the leg and problem, and drop
    a mirrored leg's issue when its source leg has one at the same field.
    """

    def split(field_path: str) -> tuple[str | None, str]:
        parts = field_path.split(".", 2)
        if len(parts) >= 2 and parts[0] == "legs":
            return parts[1], parts[2] if len(parts) == 3 else ""
        return None, field_path

    flagged = {split(issue.field) for issue in issues}
    seen: set[tuple[Path | None, int | None, str, str]] = set()
    out = []
    for issue in issues:
        leg, below = split(issue.field)
        if leg is not None and leg in mirrors and (mirrors[leg][0], below) in flagged:
            continue
        key = (issue.file, issue.line, below, issue.problem)
        if key not in seen:
            seen.add(key)
            out.append(issue)
    return out


def load_robot(name_or_path: str | Path) -> LoadedRobot:
    """Read, expand and validate a robot file (schema only; see :mod:`shc_cli.validation`)."""
    path = resolve("robots", name_or_path)
    data, documents = _read_with_extends(path)
    located = Located(path=path, origin_map=origins(data), documents=documents)
    _check_mirror_table(data, located)
    mirrors: dict[str, tuple[str, set[str]]] = {}
    data = _expand_legs(data, documents, mirrors)
    located.origin_map = origins(data)
    plain = {k: v for k, v in unwrap(data).items() if k not in FILE_KEYS}
    robot = _validate(Robot, plain, located, mirrors)
    return LoadedRobot(path=path, origin_map=located.origin_map, documents=documents, robot=robot, mirrors=mirrors)


def _check_mirror_table(data: dict[str, Any], loaded: Located) -> None:
    rules = data.get("mirror")
    if rules is None:
        return
    if not isinstance(rules, dict):
        raise SpecError([loaded.issue(("mirror",), "expected a table", "[mirror] with negate_dh and negate_joints")])
    issues = []
    for key, value in rules.items():
        if key not in ("negate_dh", "negate_joints"):
            close = difflib.get_close_matches(key, ["negate_dh", "negate_joints"], n=1)
            issues.append(loaded.issue(("mirror", key), f"unknown key '{key}'",
                                       f"did you mean '{close[0]}'?" if close else "use negate_dh or negate_joints"))
        elif not isinstance(value.value, list) or not all(isinstance(v, str) for v in value.value):
            issues.append(loaded.issue(("mirror", key), "expected a list of names", 'e.g. ["coxa", "coxat"]'))
        elif key == "negate_dh":
            for item in value.value:
                _, _, angle = item.partition(".")
                if angle not in DH_ANGLES:
                    issues.append(loaded.issue(("mirror", key), f"'{item}' is not LINK.theta or LINK.alpha",
                                               'e.g. "base.alpha" or "coxat.theta"'))
    if issues:
        raise SpecError(issues)


def load_gait(name_or_path: str | Path, relative_to: Path | None = None) -> LoadedGait:
    """Read and validate a gait file (by bundled name or path)."""
    path = resolve("gaits", name_or_path, relative_to)
    document = Document(path)
    data = document.sourced()
    located = Located(path=path, origin_map=origins(data), documents={path: document})
    gait = _validate(Gait, unwrap(data), located)
    return LoadedGait(path=path, origin_map=located.origin_map, documents=located.documents, gait=gait)


def robot_file_schema() -> dict[str, Any]:
    """JSON Schema of a robot *file*: the expanded robot plus extends/templates/mirror, legs partial."""
    schema = Robot.model_json_schema()
    defs = schema.setdefault("$defs", {})
    partial_leg = _partial(Leg.model_json_schema(), defs, ("DH", "Joint", "StanceXY"))
    partial_leg["properties"]["template"] = {"type": "string", "description": "name of a [templates.*] table"}
    partial_leg["properties"]["mirror"] = {"type": "string", "description": "id of the leg this one reflects"}
    defs["LegPatch"] = partial_leg
    schema["properties"]["legs"] = {"type": "object", "additionalProperties": {"$ref": "#/$defs/LegPatch"},
                                    "description": Robot.model_fields["legs"].description}
    schema["properties"]["templates"] = {"type": "object", "additionalProperties": {"$ref": "#/$defs/LegPatch"},
                                         "description": "leg tables that legs merge with template = NAME"}
    schema["properties"]["extends"] = {"type": "string", "description": "robot this file overrides (name or path)"}
    schema["properties"]["mirror"] = {
        "type": "object", "additionalProperties": False,
        "description": "how mirror = LEG reflects a leg; default: negate every DH theta/alpha and every joint",
        "properties": {
            "negate_dh": {"type": "array", "items": {"type": "string"}, "description": "LINK.theta / LINK.alpha"},
            "negate_joints": {"type": "array", "items": {"type": "string"}, "description": "joint names"},
        },
    }
    schema["title"] = "shc robot file"
    relaxed: dict[str, Any] = _without_required(schema)  # a file that extends another may set any subset
    return relaxed


def _without_required(node: Any) -> Any:
    """A copy of a JSON Schema with every ``required`` list removed."""
    if isinstance(node, dict):
        return {k: _without_required(v) for k, v in node.items() if k != "required"}
    if isinstance(node, list):
        return [_without_required(v) for v in node]
    return node


def _partial(leg_schema: dict[str, Any], defs: dict[str, Any], names: tuple[str, ...]) -> dict[str, Any]:
    """A copy of the leg schema with no required fields (partial DH/joint tables allowed)."""
    for name, sub in leg_schema.pop("$defs", {}).items():
        if name in names:
            relaxed = dict(sub)
            relaxed.pop("required", None)
            defs[f"{name}Patch"] = relaxed
    text = json.dumps(leg_schema)
    for name in names:
        text = text.replace(f'"#/$defs/{name}"', f'"#/$defs/{name}Patch"')
    out: dict[str, Any] = json.loads(text)
    out.pop("required", None)
    out["title"] = "LegPatch"
    return out


__all__ = ["DH", "Joint", "LoadedGait", "LoadedRobot", "bundled", "load_gait", "load_robot", "one_per_mistake",
           "resolve"]
