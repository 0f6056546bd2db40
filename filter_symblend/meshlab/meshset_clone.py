"""A working copy of a MeshSet, for rehearsing a filter script before touching the real one.

pymeshlab has no way to copy a MeshSet or to undo a filter, and layer ids
only ever grow (``clear`` resets them), so a failed script cannot be rolled
back inside the MeshSet it ran on. The runner rehearses on this copy instead.

Copied: layer ids and labels, the current layer, vertices, faces, edges,
normals, colours, quality, texture coordinates, vertex and face selection,
custom per-vertex and per-face attributes (scalar and point). Not copied:
texture images, layer visibility, rasters, transform matrices.
"""

from __future__ import annotations

import numpy as np
import pymeshlab

from .attributes import custom_attribute_names

_VERTEX_SELECTED = "symblend_clone_vertex_selected"
_FACE_SELECTED = "symblend_clone_face_selected"


def _copy_of(mesh: pymeshlab.Mesh) -> pymeshlab.Mesh:
    arrays = {"vertex_matrix": mesh.vertex_matrix(), "face_matrix": mesh.face_matrix(),
              "edge_matrix": mesh.edge_matrix(), "v_normals_matrix": mesh.vertex_normal_matrix()}
    if mesh.face_number():
        arrays["f_normals_matrix"] = mesh.face_normal_matrix()
    optional = {"v_scalar_array": (mesh.has_vertex_scalar, mesh.vertex_scalar_array),
                "v_color_matrix": (mesh.has_vertex_color, mesh.vertex_color_matrix),
                "f_scalar_array": (mesh.has_face_scalar, mesh.face_scalar_array),
                "f_color_matrix": (mesh.has_face_color, mesh.face_color_matrix)}
    arrays.update({key: read() for key, (present, read) in optional.items() if present()})
    if mesh.has_vertex_tex_coord():
        arrays["v_tex_coords_matrix"] = mesh.vertex_tex_coord_matrix()
    if mesh.has_wedge_tex_coord():
        arrays["w_tex_coords_matrix"] = mesh.wedge_tex_coord_matrix()
    return pymeshlab.Mesh(**arrays)


def _copy_layer(source: pymeshlab.MeshSet, clone: pymeshlab.MeshSet, mesh_id: int) -> None:
    source.set_current_mesh(mesh_id)
    mesh = source.current_mesh()
    attributes = custom_attribute_names(source)
    clone.add_mesh(_copy_of(mesh), mesh.label())
    copy = clone.current_mesh()
    for name in attributes["vs"]:
        copy.add_vertex_custom_scalar_attribute(mesh.vertex_custom_scalar_attribute_array(name), name)
    for name in attributes["vp"]:
        copy.add_vertex_custom_point_attribute(mesh.vertex_custom_point_attribute_matrix(name), name)
    for name in attributes["fs"]:
        copy.add_face_custom_scalar_attribute(mesh.face_custom_scalar_attribute_array(name), name)
    for name in attributes["fp"]:
        copy.add_face_custom_point_attribute(mesh.face_custom_point_attribute_matrix(name), name)
    if mesh.face_number() and mesh.selected_face_number():
        copy.add_face_custom_scalar_attribute(mesh.face_selection_array().astype(float), _FACE_SELECTED)
        clone.compute_selection_by_condition_per_face(condselect=f"{_FACE_SELECTED} > 0")
    if mesh.selected_vertex_number():
        copy.add_vertex_custom_scalar_attribute(mesh.vertex_selection_array().astype(float), _VERTEX_SELECTED)
        clone.compute_selection_by_condition_per_vertex(condselect=f"{_VERTEX_SELECTED} > 0")


def clone_meshset(source: pymeshlab.MeshSet) -> pymeshlab.MeshSet:
    """A new MeshSet with the same layers under the same ids, and the same current layer."""
    clone = pymeshlab.MeshSet()
    ids = [mesh.id() for mesh in source]
    if not ids:
        return clone
    current = source.current_mesh_id()
    placeholders = []
    try:
        for mesh_id in range(max(ids) + 1):  # ids are given in order from 0: fill the gaps
            if mesh_id in ids:
                _copy_layer(source, clone, mesh_id)
            else:
                clone.add_mesh(pymeshlab.Mesh(np.zeros((1, 3))))
                placeholders.append(mesh_id)
            assert clone.current_mesh_id() == mesh_id, "pymeshlab no longer numbers layers from 0"
    finally:
        source.set_current_mesh(current)
    for mesh_id in placeholders:
        clone.set_current_mesh(mesh_id)
        clone.delete_current_mesh()
    clone.set_current_mesh(current)
    return clone
