"""Mirror maps: where each point of a surface has its mirror twin, as a function on positions.

A map lives in one space (a :class:`Surface`: the input, or a symmetrized output),
predicts twin positions there, and knows the global mirror direction, which tells
the left side (the direction's side) from the right. Three are tried on a shape
with no landmarks, in this order, each only when the one before leaves much of the
surface without a mirror image: reflection across the best mirror plane; the same
in whitened coordinates (an affine mirror map: a shape compressed or sheared as a
whole); and the reflection registered onto the shape (a smooth non-rigid map: bends,
bends with compression); on a mesh whose tessellation mirrors itself, the mirror map of
its connectivity (:mod:`.connectivity`), between its pairs. Later rounds use the plane
of the symmetrized output.
"""

from __future__ import annotations

from collections.abc import Callable
import dataclasses

import numpy as np

from ..checks.surface_asymmetry import fit_surface_mirror_plane
from ..core.geometry import normalize, reflection_across_plane, whitening
from .config import AutoConfig
from .registration import coherent_point_drift, registration_sample
from .surface import Surface


@dataclasses.dataclass(frozen=True)
class MirrorMap:
    """``predict`` (m, 3) -> (m, 3): predicted twin positions in ``surface``'s space; ``normal`` (3,):
    the global mirror direction there, pointing to the left side; ``linear`` (3, 3): the map's linear part
    as a whole (a reflection, an affine involution), which carries a normal at a point to about the normal
    at its twin (by its inverse transpose)."""

    name: str
    surface: Surface
    predict: Callable[[np.ndarray], np.ndarray]
    normal: np.ndarray
    linear: np.ndarray

    def mirror_normals(self, normals: np.ndarray) -> np.ndarray:
        """Unit normals (m, 3) at the twins, about, of the normals (m, 3)."""
        return normalize(normals @ np.linalg.inv(self.linear))


def plane_map(surface: Surface, normal: np.ndarray, offset: float, name: str = "mirror plane") -> MirrorMap:
    """Reflection across the plane normal . x = offset."""
    normal = normalize(np.asarray(normal, dtype=float))
    reflection = np.eye(3) - 2.0 * np.outer(normal, normal)
    return MirrorMap(name, surface, lambda x: reflection_across_plane(x, normal, offset), normal, reflection)


def affine_map(surface: Surface) -> MirrorMap:
    """The mirror plane of the whitened shape, mapped back: an affine involution. A mirror-symmetric shape
    under any affine map is symmetric under such a map, and whitened (covariance the identity), its
    symmetry is an orthogonal reflection again, the covariance being invariant under the symmetry."""
    used = surface.points[surface.usable_index]
    centre = used.mean(axis=0)
    forward = whitening(used)
    backward = np.linalg.pinv(forward)
    normal, offset = fit_surface_mirror_plane((used - centre) @ forward)

    def predict(x: np.ndarray) -> np.ndarray:
        return reflection_across_plane((x - centre) @ forward, normal, offset) @ backward + centre

    linear = forward @ (np.eye(3) - 2.0 * np.outer(normal, normal)) @ backward  # x -> x @ linear
    return MirrorMap("whitened mirror plane", surface, predict, normalize(backward @ normal), linear.T)


def pairs_map(surface: Surface, partner: np.ndarray, normal: np.ndarray, config: AutoConfig,
              name: str) -> MirrorMap:
    """The mirror map of known vertex pairs ``partner`` (N,) (twin index, -1 unpaired), between them: at
    each position the local affine map of the nearest pairs (see :mod:`.growth`)."""
    from scipy.spatial import cKDTree

    from .growth import local_maps

    paired = np.flatnonzero(partner >= 0)
    tree = cKDTree(surface.points[paired])

    def predict(x: np.ndarray) -> np.ndarray:
        return local_maps(surface.points, partner, x, paired, tree, config.local_neighbours)[0]

    normal = normalize(np.asarray(normal, dtype=float))
    return MirrorMap(name, surface, predict, normal, np.eye(3) - 2.0 * np.outer(normal, normal))


def registered_map(start: MirrorMap, config: AutoConfig, screening: bool = False) -> MirrorMap:
    """The map ``start`` (a plane, an affine map), corrected by a smooth field that moves its predictions
    onto the shape (coherent point drift, :mod:`.registration`) on ``config.registration_samples`` spread
    vertices; ``screening``: on half of them and with half the iterations, to compare starts."""
    surface = start.surface
    share = 2 if screening else 1
    sample = registration_sample(surface, config.registration_samples // share)
    points, normals = surface.points[sample], surface.normals[sample]
    field = coherent_point_drift(points, start.predict(points), normals, start.mirror_normals(normals),
                                 0.3 * surface.spacing, config.registration_iterations // share)
    return MirrorMap(f"registration from the {start.name}", surface, lambda x: field(start.predict(x)), start.normal,
                     start.linear)
