"""Before/after checks of a symmetrization: Hausdorff between the meshes, mirror asymmetry of each."""

from __future__ import annotations

import numpy as np
import pymeshlab

from .asymmetry import fit_mirror_plane
from .attributes import optional_attribute
from .hausdorff import two_way_hausdorff
from .landmarks import pairs_from_attribute
from .parameters import DEFAULTS
from .surface_symmetry import mirror_asymmetry


def _landmark_plane(mesh: pymeshlab.Mesh, pair_attribute: str):
    labels = optional_attribute(mesh, pair_attribute)
    if labels is None or np.count_nonzero(labels) < 6:
        return None
    pairs = pairs_from_attribute(labels, pair_attribute)
    points = mesh.vertex_matrix()
    return fit_mirror_plane(points[pairs.left], points[pairs.right])


def compare_layers(ms: pymeshlab.MeshSet, before: int, after: int,
                   pair_attribute: str = DEFAULTS["pair_attribute"]) -> dict:
    """``{"hausdorff_before_after", "mirror_asymmetry_before", "mirror_asymmetry_after"}`` for two
    layers of ``ms``; each mirror asymmetry also holds ``per_vertex`` (N,). The planes start from
    the landmark pairs when a layer carries ``pair_attribute``. The layers are not changed."""
    result = {"hausdorff_before_after": two_way_hausdorff(ms, before, after)}
    for key, mesh_id in (("mirror_asymmetry_before", before), ("mirror_asymmetry_after", after)):
        mesh = ms.mesh(mesh_id)
        result[key] = mirror_asymmetry(mesh.vertex_matrix(), mesh.face_matrix(),
                                       _landmark_plane(mesh, pair_attribute))
    return result
