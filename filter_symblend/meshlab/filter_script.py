"""MeshLab filter scripts (.mlx): read and write them, and our own node.

A script is a list of :class:`FilterNode`. Our node's ``<Param>`` elements come from the one parameter
declaration (``symblend_node``, ``symblend_options``); MeshLab's own nodes become pymeshlab calls in
``native_calls``.
"""

from __future__ import annotations

import dataclasses
import difflib
import pathlib
import xml.etree.ElementTree as ElementTree

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
        if element.tag not in ("filter", "xmlfilter") or "name" not in element.attrib:
            raise ScriptError(f"{path}, element {position}: expected <filter name=\"...\"> (or MeshLab's "
                              f"older <xmlfilter name=\"...\">), got <{element.tag}>.")
        node = node_from_element(element, position)
        if element.tag == "filter" and any("name" not in p or "type" not in p for p in node.params):
            raise ScriptError(f"{node.where(path)}: every <Param> needs a name and a type.")
        if element.tag == "xmlfilter" and any("name" not in p or "value" not in p for p in node.params):
            raise ScriptError(f"{node.where(path)}: every <xmlparam> needs a name and a value.")
        nodes.append(node)
    return nodes


def node_from_element(element: ElementTree.Element, position: int) -> FilterNode:
    """A ``<filter>`` element as a node, its ``<Param>`` attributes kept exactly as written; an
    ``<xmlfilter>`` (MeshLab up to 2020.05) likewise, its ``<xmlparam>`` without a type."""
    tag = "xmlparam" if element.tag == "xmlfilter" else "Param"
    return FilterNode(element.attrib["name"], [dict(p.attrib) for p in element if p.tag == tag], position)


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
