"""Run MeshLab filter scripts that mix native filters and ours; save pipelines as scripts.

``apply_filter_script`` checks the whole script first (filter names,
parameter names, types and values), then rehearses it on a copy of the
MeshSet (``meshset_clone``), and only when every step succeeded there runs it
on the MeshSet itself, reusing our filter's results from the rehearsal. So a
failing script leaves the MeshSet exactly as it was: pymeshlab cannot undo a
filter, and its own ``apply_filter_script`` stops half-way.
"""

from __future__ import annotations

import pymeshlab

from ..errors import MeshSetError, SymblendError
from .meshset_clone import clone_meshset
from .meshset_filter import DISPLAY_NAME, run_filter
from .filter_script import (FilterNode, ScriptError, node_from_element, read_filter_script, symblend_node,
                            symblend_options, write_filter_script)
from .native_calls import NativeCall, native_call
from .recording import recorded_calls, recorded_native_script


def _plan(nodes: list[FilterNode], path, accept_replacements: bool) -> list:
    return [(node, symblend_options(node, path)) if node.is_symblend
            else native_call(node, path, accept_replacements) for node in nodes]


def _layers(ms: pymeshlab.MeshSet) -> str:
    return ", ".join(str(mesh.id()) for mesh in ms) or "none"


def _run(ms: pymeshlab.MeshSet, plan: list, path, cache: dict, progress) -> list[dict]:
    results = []
    for step in plan:
        if isinstance(step, NativeCall):
            node = step.node
            for name, mesh_id in step.mesh_ids.items():
                if not ms.mesh_id_exists(mesh_id):  # pymeshlab would crash the interpreter
                    raise ScriptError(f"{node.where(path)}: parameter `{name}` refers to layer {mesh_id}, "
                                      f"which does not exist at this step (layers: {_layers(ms)}).")
            try:
                output = ms.apply_filter(step.filter_name, **step.values) if step.filter_name else None
            except pymeshlab.PyMeshLabException as error:
                raise ScriptError(f"{node.where(path)}: MeshLab failed: {' '.join(str(error).split())}") from None
            if step.note:
                results.append({"filter": node.name, "output": output, "translated": step.note})
                continue
        else:
            node, options = step
            try:
                output = run_filter(ms, options, progress, cache).to_dict()
            except SymblendError as error:
                raise ScriptError(f"{node.where(path)}: {error}") from None
        results.append({"filter": node.name, "output": output})
    return results


def apply_filter_script(ms: pymeshlab.MeshSet, path, progress=None, accept_replacements: bool = False) -> list[dict]:
    """Run the .mlx script ``path`` on ``ms``: native MeshLab filters through pymeshlab, our
    node ("{display}") in Python, in order.

    Returns one ``{"filter": name, "output": ...}`` per node (what the filter
    returned: measures, our report), with ``"translated"`` saying how a filter
    of an earlier MeshLab version was run (renamed, parameters translated),
    or, with ``accept_replacements``, what replaced a filter MeshLab removed
    (only where the history records a replacement; otherwise it is refused).
    Raises ScriptError naming the node and the problem; the MeshSet is then
    unchanged.
    """
    plan = _plan(read_filter_script(path), path, accept_replacements)
    if ms.mesh_number() == 0:
        raise MeshSetError("The MeshSet is empty: load the mesh the script works on first.")
    cache: dict = {}
    _run(clone_meshset(ms), plan, path, cache, progress)
    try:
        return _run(ms, plan, path, cache, None)
    except SymblendError as error:  # the rehearsal passed: only a non-deterministic filter gets here
        raise ScriptError(f"{error} This step succeeded on the rehearsal copy but not on the MeshSet; "
                          "the MeshSet may be partly changed.") from None


apply_filter_script.__doc__ = apply_filter_script.__doc__.replace("{display}", DISPLAY_NAME)


def save_filter_script(ms: pymeshlab.MeshSet, path) -> None:
    """Save what has been applied to ``ms`` as a .mlx script: pymeshlab's recording of the native
    filters, with each call of our filter written as our node (all parameters), in order."""
    native = list(recorded_native_script(ms))
    nodes, index = [], 0
    for start, end, options in recorded_calls(ms):
        if end > len(native) or start < index or native[start].attrib.get("name") != "Duplicate Current layer":
            raise ScriptError(
                "The MeshSet's recorded filter script no longer matches the calls of our filter (it was "
                "cleared or replaced, e.g. by ms.clear_filter_script() or ms.load_filter_script()); "
                "build the pipeline again on a fresh MeshSet to record it.")
        nodes += [node_from_element(e, len(nodes) + i + 1) for i, e in enumerate(native[index:start])]
        nodes.append(symblend_node(options, len(nodes) + 1))
        index = end
    nodes += [node_from_element(e, len(nodes) + i + 1) for i, e in enumerate(native[index:])]
    write_filter_script(nodes, path)
