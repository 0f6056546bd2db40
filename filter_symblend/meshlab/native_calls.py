"""MeshLab's own nodes of a filter script as pymeshlab calls (``ms.apply_filter(python_name, **values)``):
their names resolved across MeshLab versions (filter_names), renamed or replaced filters translated, their
parameters checked and converted to pymeshlab's types."""

from __future__ import annotations

import dataclasses
import difflib
import functools

import numpy as np
import pymeshlab

from . import filter_names
from .filter_names import python_name
from .filter_script import FilterNode, ScriptError
from .meshset_filter import DISPLAY_NAME


def _translated(node: FilterNode, now: str, parameters: dict, added: dict) -> tuple[FilterNode, list[str], list[dict]]:
    """``node`` as the filter ``now``: its parameters renamed and their values translated by ``parameters``
    (see filter_names.Rename), ``added`` appended where not given; with the "old -> new" names changed and
    the parameters added."""
    params, changed = [], []
    for param in node.params:
        change = parameters.get(param["name"])
        if change:
            changed.append(f"{param['name']} -> {change.get('name', param['name'])}")
            param = dict(param, name=change.get("name", param["name"]), type=change.get("type", param.get("type")),
                         value=change.get("values", {}).get(str(param.get("value")).lower(), param.get("value")))
        params.append(param)
    given = {python_name(p["name"]) for p in params}
    extra = [dict(value, name=name) for name, value in added.items() if python_name(name) not in given]
    return FilterNode(now, params + extra, node.position), changed, extra


def _old_node_now(node: FilterNode, accept_replacements: bool) -> tuple[FilterNode | None, str | None]:
    """The node in today's MeshLab terms (None: a removed step dropped, as accepted), and a note saying
    what was translated or replaced (None if nothing)."""
    rename = filter_names.renamed(node.name)
    if rename is not None:
        now, changed, added = _translated(node, rename.now, rename.parameters, rename.added)
        if python_name(rename.old) == python_name(rename.now) and not changed and not added:
            return node, None  # today's form of a filter whose parameters were renamed
        note = f"'{rename.old}' (MeshLab {rename.seen_in}) runs as today's '{rename.now}'"
        return now, note + (f", parameters translated: {', '.join(changed)}" if changed else "")
    gone = filter_names.removed(node.name)
    if not accept_replacements or gone is None or gone.replacement is None:
        return node, None
    replacement = gone.replacement
    note = f"'{node.name}' (removed in MeshLab {gone.dropped_in})"
    if replacement.now is None:
        return None, f"{note} dropped, as accepted: {gone.instead}"
    dropped = {python_name(name): (name, why) for name, why in replacement.dropped.items()}
    kept = [p for p in node.params if python_name(p["name"]) not in dropped]
    now, changed, added = _translated(FilterNode(node.name, kept, node.position), replacement.now,
                                      replacement.parameters, replacement.added)
    note += f" replaced, as accepted, by '{replacement.now}'"
    note += f"; parameters translated: {', '.join(changed)}" if changed else ""
    note += f"; added: {', '.join(p['name'] + '=' + p['value'] for p in added)}" if added else ""
    gone_values = [f"{p['name']}={p.get('value')} ({dropped[python_name(p['name'])][1]})" for p in node.params
                   if python_name(p["name"]) in dropped]
    return now, note + (f"; not carried over: {', '.join(gone_values)}" if gone_values else "")


def unknown_filter_message(node: FilterNode, path) -> str:
    gone = filter_names.removed(node.name)
    if gone is not None:
        instead = f" Instead: {gone.instead}." if gone.instead else " It has no successor; drop the step."
        accept = (" To run the replacement, accept it: symblend mlx --accept-replacements (Python: "
                  "apply_filter_script(..., accept_replacements=True))." if gone.replacement else "")
        return f"{node.where(path)}: MeshLab removed this filter in {gone.dropped_in}.{instead}{accept}"
    close = filter_names.closest_filter(node.name, {python_name(DISPLAY_NAME): DISPLAY_NAME})
    hint = ""
    if close and close[1] is None:
        hint = f' Did you mean "{DISPLAY_NAME}" (our filter)?'
    elif close:
        shown = f"'{close[0]}' (pymeshlab: {close[1]})" if close[0] else f"pymeshlab's {close[1]}"
        hint = (f" The closest MeshLab filter is {shown}; write its name as MeshLab's Filters menu "
                "or a script saved by MeshLab spells it.")
    return f"{node.where(path)}: no version of MeshLab had a filter of this name.{hint}"


@functools.lru_cache(maxsize=None)
def native_parameter_types(filter_name: str) -> dict[str, type]:
    """Python type of each parameter of a pymeshlab filter (defaults taken on a small cube)."""
    scratch = pymeshlab.MeshSet()
    scratch.create_cube()
    return {name: type(value) for name, value in scratch.filter_parameter_values(filter_name).items()}


# .mlx parameter type -> (the Python type pymeshlab reports, converter from the <Param> attributes)
def _floats(param: dict, keys: list[str]) -> np.ndarray:
    return np.array([float(param[k]) for k in keys])


_NATIVE_TYPES = {
    "RichBool": (bool, lambda p: {"true": True, "false": False}[p["value"].lower()]),
    "RichInt": (int, lambda p: int(p["value"])),
    "RichEnum": (int, lambda p: int(p["value"])),
    "RichMesh": (int, lambda p: int(p["value"])),
    "RichFloat": (float, lambda p: float(p["value"])),
    "RichDynamicFloat": (float, lambda p: float(p["value"])),
    "RichAbsPerc": (float, lambda p: pymeshlab.PureValue(float(p["value"]))),
    "RichString": (str, lambda p: p["value"]),
    "RichOpenFile": (str, lambda p: p["value"]),
    "RichSaveFile": (str, lambda p: p["value"]),
    "RichFileOpen": (str, lambda p: p["value"]),
    "RichFileSave": (str, lambda p: p["value"]),
    "RichPosition": (np.ndarray, lambda p: _floats(p, ["x", "y", "z"])),
    "RichPoint3f": (np.ndarray, lambda p: _floats(p, ["x", "y", "z"])),
    "RichDirection": (np.ndarray, lambda p: _floats(p, ["x", "y", "z"])),
    "RichMatrix44f": (np.ndarray, lambda p: _floats(p, [f"val{i}" for i in range(16)]).reshape(4, 4)),
    "RichColor": (pymeshlab.Color, lambda p: pymeshlab.Color(*(int(p[k]) for k in "rgba"))),
}


# The .mlx type an <xmlparam> (which has none) is read as, by the Python type pymeshlab expects.
_XML_PARAM_TYPES = {bool: "RichBool", int: "RichInt", float: "RichFloat", str: "RichString"}


@dataclasses.dataclass
class NativeCall:
    """A checked native node (as written): ``ms.apply_filter(filter_name, **values)``, or nothing when
    ``filter_name`` is None (a removed step dropped, as accepted); ``mesh_ids`` name the parameters that
    refer to layers (checked to exist just before the call); ``note`` says how a filter of an earlier
    MeshLab was translated or replaced (None if it was not)."""

    node: FilterNode
    filter_name: str | None
    values: dict
    mesh_ids: dict[str, int]
    note: str | None = None


def native_call(node: FilterNode, path, accept_replacements: bool = False) -> NativeCall:
    """Check a native node against pymeshlab's own parameter list and convert its values; a filter
    of an earlier MeshLab runs as the filter it is now, its parameters translated; a removed filter
    with a recorded replacement runs as it when ``accept_replacements``."""
    written = node
    node, note = _old_node_now(node, accept_replacements)
    if node is None:
        return NativeCall(written, None, {}, {}, note)
    filter_name = filter_names.pymeshlab_filter_name(node.name)
    if filter_name is None:
        raise ScriptError(unknown_filter_message(written, path))
    expected = native_parameter_types(filter_name)
    values, mesh_ids = {}, {}
    for param in node.params:
        name = python_name(param["name"])
        if name not in expected:
            close = difflib.get_close_matches(name, list(expected), n=1)
            hint = f" Did you mean `{close[0]}`?" if close else ""
            raise ScriptError(f"{written.where(path)}: the filter has no parameter `{param['name']}`.{hint} "
                              f"Its parameters: {', '.join(expected) or 'none'}.")
        kind = param.get("type") or _XML_PARAM_TYPES.get(expected[name])
        if kind is None:
            raise ScriptError(f"{written.where(path)}: <xmlparam> `{param['name']}` has no type, and pymeshlab "
                              f"expects {expected[name].__name__}; write it as a <Param> with its type.")
        if kind not in _NATIVE_TYPES:
            raise ScriptError(f"{written.where(path)}: parameter `{param['name']}` has type {kind}, which "
                              f"this runner does not support ({', '.join(_NATIVE_TYPES)}).")
        python_type, convert = _NATIVE_TYPES[kind]
        if python_type is not expected[name]:
            raise ScriptError(
                f"{written.where(path)}: parameter `{param['name']}` is given as {kind} but pymeshlab expects "
                f"{expected[name].__name__} (a {kind} value would run with garbage); fix its type.")
        try:
            values[name] = convert(param)
        except (KeyError, ValueError):
            raise ScriptError(f"{written.where(path)}: parameter `{param['name']}` ({kind}) has an invalid "
                              f"value: {param.get('value')!r}.") from None
        if kind == "RichMesh":
            mesh_ids[param["name"]] = values[name]
    return NativeCall(written, filter_name, values, mesh_ids, note)

