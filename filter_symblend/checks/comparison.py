"""Before/after checks of a symmetrization: Hausdorff between the meshes, mirror asymmetry of each."""

from __future__ import annotations

import numpy as np
import pymeshlab

from ..core.landmark_asymmetry import MirrorFit
from ..core.landmark_pairs import pairs_from_attribute
from ..meshlab.attributes import optional_attribute
from ..parameters import DEFAULTS
from .hausdorff import two_way_distance
from .surface_asymmetry import CHECK_SAMPLES, fit_surface_mirror_plane, mirror_asymmetry, mirror_plane_from_pairs


def _mirror_plane(mesh: pymeshlab.Mesh, pair_attribute: str, start) -> tuple[np.ndarray, float]:
    """The mesh's mirror plane: refined from its landmark pairs' plane when it carries them, else
    fitted from the principal planes and ``start`` (the other mesh's plane), else fitted from scratch."""
    points = mesh.vertex_matrix()
    labels = optional_attribute(mesh, pair_attribute)
    if labels is not None and np.count_nonzero(labels) >= 6:
        pairs = pairs_from_attribute(labels, pair_attribute)
        return mirror_plane_from_pairs(points, pairs.left, pairs.right)
    return fit_surface_mirror_plane(points, None if start is None else MirrorFit(*start, np.zeros(0)))


def compare_layers(ms: pymeshlab.MeshSet, before: int, after: int,
                   pair_attribute: str = DEFAULTS["pair_attribute"], samples: int | None = CHECK_SAMPLES) -> dict:
    """``{"hausdorff_before_after", "mirror_asymmetry_before", "mirror_asymmetry_after"}`` for two
    layers of ``ms``; each mirror asymmetry is measured at ``samples`` evenly strided vertices (None:
    all) and holds their distances as ``per_vertex``. Each plane is refined from
    the layer's landmark pairs (``pair_attribute``) when it carries them; otherwise the first layer's
    is fitted and the second's refined from it. The layers are not changed."""
    result = {"hausdorff_before_after": two_way_distance(ms.mesh(before).vertex_matrix(), ms.mesh(before).face_matrix(),
                                                         ms.mesh(after).vertex_matrix(), ms.mesh(after).face_matrix())}
    plane = None
    for key, mesh_id in (("mirror_asymmetry_before", before), ("mirror_asymmetry_after", after)):
        mesh = ms.mesh(mesh_id)
        plane = _mirror_plane(mesh, pair_attribute, plane)
        result[key] = mirror_asymmetry(mesh.vertex_matrix(), mesh.face_matrix(), plane=plane, samples=samples)
    return result
