"""The pymeshlab face of the filter: read the pairs from the current mesh, run
:func:`symmetrize`, add the warped mesh as one new layer.

The input layer is never modified. The output is built from a copy of the
input (so colours, UVs, textures and selection survive), its coordinates and
quality set through MeshLab's own per-vertex function filters, then copied once
more to drop the scratch attributes (pymeshlab cannot delete attributes; the
copy drops custom attributes). On any failure every layer the filter added is
deleted and the input is current again.
"""

from __future__ import annotations

import inspect

import pymeshlab

from .attributes import optional_attribute, read_landmark_attributes
from .errors import MeshSetError, ParameterError
from .parameters import keyword_signature, parameters_doc, validate_parameters
from .symmetrize import symmetrize

FILTER_NAME = "generate_symmetrized_mesh"
DISPLAY_NAME = "Symmetrize: Closed-form Blending of Local Symmetries"
ASYMMETRY_ATTRIBUTE = "symblend_asymmetry"
_SCRATCH = ("symblend_scratch_x", "symblend_scratch_y", "symblend_scratch_z",
            "symblend_scratch_quality")


def _add_output_layer(ms: pymeshlab.MeshSet, input_id: int, result, carried: dict) -> int:
    created = []
    try:
        ms.set_current_mesh(input_id)
        label = ms.current_mesh().label()
        ms.generate_copy_of_current_mesh()
        created.append(ms.current_mesh_id())
        scratch = ms.current_mesh()
        for name, values in zip(_SCRATCH, [*result.points.T, result.asymmetry]):
            scratch.add_vertex_custom_scalar_attribute(values, name)
        ms.compute_coord_by_function(x=_SCRATCH[0], y=_SCRATCH[1], z=_SCRATCH[2], onselected=False)
        ms.compute_scalar_by_function_per_vertex(q=_SCRATCH[3], onselected=False)
        ms.generate_copy_of_current_mesh()
        created.append(ms.current_mesh_id())
        output = ms.current_mesh()
        output.add_vertex_custom_scalar_attribute(result.asymmetry, ASYMMETRY_ATTRIBUTE)
        for name, values in carried.items():
            output.add_vertex_custom_scalar_attribute(values, name)
        if not output.is_point_cloud():
            ms.compute_normal_per_face()
            ms.compute_normal_per_vertex()
        output.set_label(f"{label}_symmetrized")
        output_id = created[1]
        ms.set_current_mesh(created.pop(0))
        ms.delete_current_mesh()
        ms.set_current_mesh(output_id)
        return output_id
    except BaseException:
        for mesh_id in created:
            ms.set_current_mesh(mesh_id)
            ms.delete_current_mesh()
        ms.set_current_mesh(input_id)
        raise


def generate_symmetrized_mesh(ms: pymeshlab.MeshSet, progress=None, **params) -> dict:
    options = validate_parameters(params)
    if ms.mesh_number() == 0:
        raise MeshSetError(
            "The MeshSet has no current mesh. Load one first, e.g. ms.load_new_mesh('skull.ply')."
        )
    input_id = ms.current_mesh_id()
    mesh = ms.current_mesh()
    attributes = {name: options.pop(name) for name in ("pair_attribute", "midline_attribute", "weight_attribute")}
    names = list(attributes.values())
    if len(set(names)) < len(names) or ASYMMETRY_ATTRIBUTE in names:
        raise ParameterError(
            f"`pair_attribute`, `midline_attribute` and `weight_attribute` must be three different "
            f"names, none of them `{ASYMMETRY_ATTRIBUTE}` (the filter writes it); got {', '.join(names)}.")
    pairs, left_weights, right_weights = read_landmark_attributes(mesh, **attributes)
    result = symmetrize(mesh.vertex_matrix(), pairs.left, pairs.right, pairs.ids, pairs.midline,
                        left_weights, right_weights, progress, **options)
    carried = {name: values for name in attributes.values()
               if (values := optional_attribute(mesh, name)) is not None}
    output_id = _add_output_layer(ms, input_id, result, carried)
    return {**result.report, "input_mesh_id": input_id, "output_mesh_id": output_id}


_PROGRESS = inspect.Parameter("progress", inspect.Parameter.KEYWORD_ONLY, default=None)
generate_symmetrized_mesh.__signature__ = keyword_signature(
    inspect.Parameter("ms", inspect.Parameter.POSITIONAL_ONLY), _PROGRESS)
generate_symmetrized_mesh.__doc__ = f"""{DISPLAY_NAME}.

Symmetrizes the current mesh from the landmark pairs in its per-vertex scalar
attribute (Ghosh, Amenta, Kazhdan, SGP 2010) and adds the warped mesh as a new
layer, which becomes current. Same vertices (count and order), faces, colours,
UVs and textures as the input; per-vertex quality and the custom attribute
``{ASYMMETRY_ATTRIBUTE}`` hold how far each vertex moved (local asymmetry, in
mesh units, input frame); the pair, midline and weight attributes are
carried over. The input layer
is never modified; on error the MeshSet is left exactly as it was.

Parameters
----------
{parameters_doc()}
progress : callable(percent: float, message: str), optional
    Called at each stage (not a filter parameter: it is not saved in scripts).

Returns
-------
dict
    The report of :func:`filter_symblend.symmetrize` plus ``input_mesh_id`` and
    ``output_mesh_id``.
"""


def _meshset_method(self, progress=None, **params):
    return generate_symmetrized_mesh(self, progress, **params)


_meshset_method.__name__ = FILTER_NAME
_meshset_method.__qualname__ = f"MeshSet.{FILTER_NAME}"
_meshset_method.__doc__ = generate_symmetrized_mesh.__doc__
_meshset_method.__signature__ = keyword_signature(
    inspect.Parameter("self", inspect.Parameter.POSITIONAL_ONLY), _PROGRESS)


def bind_to_meshset() -> None:
    """Add ``MeshSet.generate_symmetrized_mesh`` (pymeshlab binds its own filters the same way)."""
    setattr(pymeshlab.MeshSet, FILTER_NAME, _meshset_method)
