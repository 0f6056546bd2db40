"""Which thin-plate spline carries the mesh, by the number of landmarks k (measured on 2 cores, Igea
with the paper's Figure 1 map, docs/benchmarks.md#dense-pairs):

- k <= EXACT_CENTRES: the dense LU of the spline's system (core/warp/splines.py), O(k^3): 0.2 s at 2,000;
- k <= ITERATIVE_CENTRES: the same spline by a preconditioned iteration (core/warp/iterative.py), O(k^2) per step,
  within 1e-6 of the diagonal of the dense one: faster than the LU above EXACT_CENTRES (the two cross between
  2,000 and 3,500 landmarks, fit and evaluation at 5,000 vertices: 0.21 against 0.27 s at 2,000, 0.50 against
  0.44 s at 3,000, 0.79 against 0.50 s at 3,500, 1.8-2.0 against 0.74-0.88 s at 5,000, where the LU's matrix
  leaves the cache);
- beyond: the approximation (core/warp/splines.py), exact at the landmarks, about 2e-4 of the diagonal from
  the exact spline: its cost grows as k, the iteration's as k^2 per step.
A flat input takes the spline of its plane whatever k.
"""

from __future__ import annotations

import numpy as np

from .iterative import iterative_thin_plate_spline
from .splines import ApproximateThinPlateSpline, PlanarThinPlateSpline, ThinPlateSpline

EXACT_CENTRES = 3_000
ITERATIVE_CENTRES = 40_000  # 20,000 pairs: an iteration step takes about 5 s beyond


def thin_plate_spline(centres: np.ndarray, values: np.ndarray, flat: np.ndarray | None = None):
    """The spline through ``values`` (k, d) at ``centres`` (k, 3), chosen by k as above; in the plane for
    a flat input (``flat``: its unit normal). Each has a ``description`` for the report."""
    if flat is not None:
        return PlanarThinPlateSpline(centres, values, flat)
    if len(centres) <= EXACT_CENTRES:
        return ThinPlateSpline(centres, values)
    if len(centres) <= ITERATIVE_CENTRES:
        return iterative_thin_plate_spline(centres, values)
    return ApproximateThinPlateSpline(centres, values)
