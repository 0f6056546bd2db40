"""The filter's output layer: a copy of the input (so colours, UVs, textures and selection survive), its
coordinates and quality set through MeshLab's own per-vertex function filters, then copied once more to
drop the scratch attributes (pymeshlab cannot delete attributes; the copy drops custom attributes), with
the attributes the filter writes. On any failure every layer added is deleted and the input is current
again."""

from __future__ import annotations

from concurrent.futures import Future

import pymeshlab

ASYMMETRY_ATTRIBUTE = "symblend_asymmetry"
TWIN_ATTRIBUTE = "symblend_twin"  # per-vertex point: the vertex's mirror twin on the output (NaN: none)
CONFIDENCE_ATTRIBUTE = "symblend_pair_confidence"  # per-vertex scalar in [0, 1] (0: no twin, or one unsupported)
UNCERTAINTY_ATTRIBUTE = "symblend_uncertainty"  # per-vertex scalar: the spread of the restored vertex, mesh units
_SCRATCH = ("symblend_scratch_x", "symblend_scratch_y", "symblend_scratch_z",
            "symblend_scratch_quality")


def add_output_layer(ms: pymeshlab.MeshSet, input_id: int, result, carried: dict,
                      pending: list[Future] = ()) -> int:
    """Add the output layer of ``result`` (a SymmetrizationResult) beside the layer ``input_id``, with the
    ``carried`` attributes ({name: (N,)}) of the input; the id of the new layer, which becomes current.
    ``pending``: work running beside it, waited for too; if it fails, the layer is removed as for a
    failure of its own."""
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
        if result.mirror_pairs is not None:  # automatic pairs: the map they came from, on the output
            twin, confidence = result.mirror_pairs.per_vertex(result.points)
            output.add_vertex_custom_point_attribute(twin, TWIN_ATTRIBUTE)
            output.add_vertex_custom_scalar_attribute(confidence, CONFIDENCE_ATTRIBUTE)
        if result.uncertainty is not None:
            output.add_vertex_custom_scalar_attribute(result.uncertainty, UNCERTAINTY_ATTRIBUTE)
        if not output.is_point_cloud():
            ms.compute_normal_per_face()
            ms.compute_normal_per_vertex()
        output.set_label(f"{label}_symmetrized")
        output_id = created[1]
        ms.set_current_mesh(created.pop(0))
        ms.delete_current_mesh()
        ms.set_current_mesh(output_id)
        for work in pending:
            work.result()
        return output_id
    except BaseException:
        for mesh_id in created:
            ms.set_current_mesh(mesh_id)
            ms.delete_current_mesh()
        ms.set_current_mesh(input_id)
        raise
