"""Landmark asymmetry: the best mirror plane of a paired configuration and the residuals.

This is the Procrustes measure of geometric morphometrics (Klingenberg): the
configuration X = [left; right] is superimposed on its reflected, relabelled
copy X* = [J right; J left] by the best rigid motion. The composite map
x -> R J x + t is the best improper isometry taking the right side onto the
left one; when the optimum is unique it is an involution, i.e. a reflection
across a plane, which is the configuration's mirror plane.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .geometry import MIRROR_X, reflection_across_plane, rigid_fit
from .report import LandmarkAsymmetry


@dataclasses.dataclass(frozen=True)
class MirrorFit:
    """Best mirror plane {x : normal . x = offset} of paired landmarks.

    ``normal`` (3,) is a unit vector pointing toward the left landmarks;
    ``deviations`` (n,) are |left_k - mirror(right_k)|, in mesh units.
    """

    normal: np.ndarray
    offset: float
    deviations: np.ndarray

    def reflect(self, points: np.ndarray) -> np.ndarray:
        """Mirror images of ``points`` (m, 3) across the plane."""
        return reflection_across_plane(points, self.normal, self.offset)

    def summary(self, diagonal: float) -> LandmarkAsymmetry:
        """RMS and max of the deviations, relative to ``diagonal`` too."""
        return LandmarkAsymmetry(float(np.sqrt(np.mean(self.deviations**2))), float(self.deviations.max()),
                                 float(diagonal))


def fit_mirror_plane(left: np.ndarray, right: np.ndarray) -> MirrorFit:
    """Best mirror plane of the pairs (left[k], right[k]); ``left``, ``right`` are (n, 3)."""
    config = np.vstack([left, right])
    reflected_relabelled = np.vstack([right, left]) @ MIRROR_X
    rotation, translation = rigid_fit(reflected_relabelled, config)
    improper = rotation @ MIRROR_X
    eigenvalues, eigenvectors = np.linalg.eigh(0.5 * (improper + improper.T))
    normal = eigenvectors[:, 0]
    if normal @ (left.mean(axis=0) - right.mean(axis=0)) < 0:
        normal = -normal
    offset = 0.5 * float(normal @ translation)
    deviations = np.linalg.norm(left - reflection_across_plane(right, normal, offset), axis=1)
    return MirrorFit(normal, offset, deviations)
