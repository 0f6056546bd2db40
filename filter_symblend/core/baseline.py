"""The classical yardstick: mirror averaging (Procrustes average of the landmark
configuration with its reflected, relabelled copy), then a thin-plate spline warp by
scipy's dense RBFInterpolator, as a scipy user would write it.

This is what geometric morphometrics does today (e.g. Morpho's symmetrize); it
makes the landmarks symmetric but undoes neither compression nor bending.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import RBFInterpolator

from .landmark_asymmetry import fit_mirror_plane


def mirror_average(points: np.ndarray, left: np.ndarray, right: np.ndarray) -> np.ndarray:
    """``points`` (N, 3) warped so that each left landmark becomes the mean of itself and its
    partner's mirror image across the configuration's best mirror plane."""
    p, q = points[left], points[right]
    plane = fit_mirror_plane(p, q)
    r = 0.5 * (p + plane.reflect(q))
    target = np.vstack([r, plane.reflect(r)])
    source = np.vstack([p, q])
    warped = points + RBFInterpolator(source, target - source, kernel="linear", degree=1)(points)
    warped[left], warped[right] = target[: len(left)], target[len(left):]
    return warped
