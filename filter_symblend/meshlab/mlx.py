"""MeshLab filter scripts (.mlx): read, write, resolve names, check and convert parameters.

A script is a list of :class:`FilterNode`. Native nodes are translated to
pymeshlab calls (``ms.apply_filter(python_name, **values)``); our node's
``<Param>`` elements come from the one parameter declaration.
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import pathlib
import xml.etree.ElementTree as ElementTree

import numpy as np
import pymeshlab

from ..atomic import write_text
from ..errors import ParameterError, SymblendError
from ..parameters import PARAMETERS, PARAMETERS_BY_NAME, validate_parameters
from .meshset_filter import DISPLAY_NAME


class ScriptError(SymblendError):
    """A filter script that cannot be read, or a node that cannot run."""


@dataclasses.dataclass
class FilterNode:
    """One ``<filter name=...>`` of a script; ``params`` are the ``<Param>`` attribute dicts."""

    name: str
    params: list[dict[str, str]]
    position: int  # 1-based, for messages

    @property
    def is_symblend(self) -> bool:
        return self.name == DISPLAY_NAME

    def where(self, path) -> str:
        return f"{path}, filter {self.position} ('{self.name}')"


def read_filter_script(path) -> list[FilterNode]:
    """The nodes of the .mlx file ``path``; ScriptError for a missing file or bad XML."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise ScriptError(f"{path}: no such filter script.")
    try:
        root = ElementTree.parse(path).getroot()
    except ElementTree.ParseError as error:
        raise ScriptError(f"{path}: not valid XML ({error}).") from None
    if root.tag != "FilterScript":
        raise ScriptError(f"{path}: the root element is <{root.tag}>, a MeshLab filter script has "
                          "<FilterScript>.")
    nodes = []
    for position, element in enumerate(root, start=1):
        if element.tag != "filter" or "name" not in element.attrib:
            raise ScriptError(f"{path}, element {position}: expected <filter name=\"...\">, got <{element.tag}>.")
        node = node_from_element(element, position)
        if any("name" not in param or "type" not in param for param in node.params):
            raise ScriptError(f"{node.where(path)}: every <Param> needs a name and a type.")
        nodes.append(node)
    return nodes


def node_from_element(element: ElementTree.Element, position: int) -> FilterNode:
    """A ``<filter>`` element as a node, its ``<Param>`` attributes kept exactly as written."""
    return FilterNode(element.attrib["name"], [dict(p.attrib) for p in element if p.tag == "Param"], position)


def write_filter_script(nodes: list[FilterNode], path) -> None:
    """Write ``nodes`` as a .mlx file, atomically (a failed write leaves no partial file)."""
    root = ElementTree.Element("FilterScript")
    for node in nodes:
        element = ElementTree.SubElement(root, "filter", name=node.name)
        for param in node.params:
            ElementTree.SubElement(element, "Param", param)
    ElementTree.indent(root, space=" ")
    write_text(path, "<!DOCTYPE FilterScript>\n" + ElementTree.tostring(root, encoding="unicode") + "\n")


# ---- our node ----------------------------------------------------------------------------------

def symblend_node(options: dict, position: int = 0) -> FilterNode:
    """Our filter as a script node, every declared parameter written (MeshLab's own format)."""
    params = []
    for p in PARAMETERS:
        value = options.get(p.name, p.default)
        param = {"name": p.name, "description": p.label, "tooltip": p.doc}
        if p.kind == "enum":
            param.update(type="RichEnum", value=str(p.choices.index(value)),
                         enum_cardinality=str(len(p.choices)),
                         **{f"enum_val{i}": choice for i, choice in enumerate(p.choices)})
        elif p.kind == "float":
            param.update(type="RichFloat", value=repr(float(value)))
        elif p.kind == "int":
            param.update(type="RichInt", value=str(int(value)))
        else:
            param.update(type="RichString", value=value)
        params.append(param)
    return FilterNode(DISPLAY_NAME, params, position)


_OUR_TYPES = {"enum": "RichEnum", "int": "RichInt", "float": "RichFloat", "string": "RichString"}


def symblend_options(node: FilterNode, path) -> dict:
    """The validated parameters of our node; unknown names, wrong types and bad values raise."""
    given = {}
    for param in node.params:
        name, kind = param["name"], param["type"]
        declared = PARAMETERS_BY_NAME.get(name)
        if declared is None:
            close = difflib.get_close_matches(name, list(PARAMETERS_BY_NAME), n=1)
            hint = f" Did you mean `{close[0]}`?" if close else ""
            raise ScriptError(f"{node.where(path)}: unknown parameter `{name}`.{hint}")
        if kind != _OUR_TYPES[declared.kind]:
            raise ScriptError(f"{node.where(path)}: parameter `{name}` has type {kind}; it must be "
                              f"{_OUR_TYPES[declared.kind]}.")
        value = param.get("value", "")
        try:
            if declared.kind == "enum":
                given[name] = declared.choices[int(value)]
            elif declared.kind == "float":
                given[name] = float(value)
            elif declared.kind == "int":
                given[name] = int(value)
            else:
                given[name] = value
        except (ValueError, IndexError):
            raise ScriptError(f"{node.where(path)}: parameter `{name}` = {value!r} is not valid "
                              f"({declared.range_text()}; an enum value is the index of the choice).") from None
    try:
        return validate_parameters(given)
    except ParameterError as error:
        raise ScriptError(f"{node.where(path)}: {error}") from None


# ---- native nodes ------------------------------------------------------------------------------

# pymeshlab's keyword list, quirk included ("def\tfrom" is one entry: neither gets a "_").
_PYTHON_KEYWORDS = {"False", "await", "else", "import", "pass", "None", "break", "except", "in", "raise",
                    "True", "class", "finally", "is", "return", "and", "continue", "for", "lambda", "try",
                    "as", "def\tfrom", "nonlocal", "while", "assert", "del", "global", "not", "with",
                    "async", "elif", "if", "or", "yield"}


def python_name(name: str) -> str:
    """pymeshlab's rule turning a MeshLab name into a Python one (its ``computePythonName``)."""
    out = name.lower().replace(" ", "_").replace("/", "_").replace("-", "_")
    out = "".join(ch for ch in out if ch not in "().,'\":+")
    return out + "_" if out in _PYTHON_KEYWORDS else out


@functools.lru_cache(maxsize=None)
def _renamed() -> dict[str, str]:
    """pymeshlab's table of 2022 renames: Python form of the MeshLab name -> current name."""
    keys = pathlib.Path(pymeshlab.__file__).with_name("keys.txt")
    if not keys.is_file():
        return {}
    return dict(line.split() for line in keys.read_text().splitlines() if len(line.split()) == 2)


def pymeshlab_filter_name(display_name: str) -> str | None:
    """The pymeshlab filter a MeshLab display name runs, or None if there is none.

    Filters added to MeshLab after pymeshlab's 2022 rename table (e.g. alpha
    wrap, the newer parametrizations) cannot be resolved from their display
    name and are reported as unknown.
    """
    snake = python_name(display_name)
    name = _renamed().get(snake, snake)
    return name if name in pymeshlab.filter_list() else None


def unknown_filter_message(node: FilterNode, path) -> str:
    known = list(_renamed()) + [python_name(DISPLAY_NAME)]
    close = difflib.get_close_matches(python_name(node.name), known, n=1, cutoff=0.6)
    hint = ""
    if close and close[0] == python_name(DISPLAY_NAME):
        hint = f' Did you mean "{DISPLAY_NAME}" (our filter)?'
    elif close:
        hint = (f" The closest MeshLab filter is '{close[0].replace('_', ' ')}' "
                f"(pymeshlab: {_renamed()[close[0]]}); write its MeshLab name as it appears in MeshLab's "
                "Filters menu or in a script saved by MeshLab.")
    return f"{node.where(path)}: no MeshLab filter has this name.{hint}"


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


@dataclasses.dataclass
class NativeCall:
    """A checked native node: ``ms.apply_filter(filter_name, **values)``; ``mesh_ids`` name the
    parameters that refer to layers (checked to exist just before the call)."""

    node: FilterNode
    filter_name: str
    values: dict
    mesh_ids: dict[str, int]


def native_call(node: FilterNode, path) -> NativeCall:
    """Check a native node against pymeshlab's own parameter list and convert its values."""
    filter_name = pymeshlab_filter_name(node.name)
    if filter_name is None:
        raise ScriptError(unknown_filter_message(node, path))
    expected = native_parameter_types(filter_name)
    values, mesh_ids = {}, {}
    for param in node.params:
        name = python_name(param["name"])
        if name not in expected:
            close = difflib.get_close_matches(name, list(expected), n=1)
            hint = f" Did you mean `{close[0]}`?" if close else ""
            raise ScriptError(f"{node.where(path)}: the filter has no parameter `{param['name']}`.{hint} "
                              f"Its parameters: {', '.join(expected) or 'none'}.")
        kind = param["type"]
        if kind not in _NATIVE_TYPES:
            raise ScriptError(f"{node.where(path)}: parameter `{param['name']}` has type {kind}, which "
                              f"this runner does not support ({', '.join(_NATIVE_TYPES)}).")
        python_type, convert = _NATIVE_TYPES[kind]
        if python_type is not expected[name]:
            raise ScriptError(
                f"{node.where(path)}: parameter `{param['name']}` is given as {kind} but pymeshlab expects "
                f"{expected[name].__name__} (a {kind} value would run with garbage); fix its type.")
        try:
            values[name] = convert(param)
        except (KeyError, ValueError):
            raise ScriptError(f"{node.where(path)}: parameter `{param['name']}` ({kind}) has an invalid "
                              f"value: {param.get('value')!r}.") from None
        if kind == "RichMesh":
            mesh_ids[param["name"]] = values[name]
    return NativeCall(node, filter_name, values, mesh_ids)

