"""The thin-plate-spline warp that carries the whole mesh along with the landmarks.

In 3D the thin-plate (biharmonic) kernel is r, i.e. scipy's RBFInterpolator
with kernel="linear" (phi(r) = -r) and a degree-1 polynomial, which reproduces
any affine map exactly. scipy evaluates it in memory-bounded chunks.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import RBFInterpolator


def thin_plate_spline_warp(source: np.ndarray, target: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``points`` (m, 3) moved by the spline that takes ``source`` (k, 3) to ``target`` (k, 3).

    The spline interpolates the displacement target - source, so where the
    landmarks do not move nothing moves; it is exact at the landmarks up to
    the rounding of its dense (k + 4) x (k + 4) solve.
    """
    displacement = RBFInterpolator(source, target - source, kernel="linear", degree=1)
    return points + displacement(points)
