"""Step 1: a local symmetrizing transform around every pair (paper Sec. 3.2, 3.3).

For pair i the neighbourhood is every pair j weighted by theta_ij (both p_j and
q_j get the same weight, so a symmetric neighbourhood stays symmetric). All
weighted sums are sparse products theta @ moments, so there is no Python loop
over pairs; the 3x3 algebra is batched (numpy eigh/svd on (n, 3, 3) stacks).

Each model returns per pair: the local mirror normal n_i, oriented from the
left (+k) side to the right (-k) side; the transforms (M_p, M_q) applied to
left and right difference vectors; the transform applied to the pair-gap
vectors in the alpha terms of Step 2; and a relative fit residual.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp

from ..errors import DegenerateNeighbourhoodError, id_list
from .geometry import normalize, proper_rotation_fit, rotation_about_axis

DEGENERATE_RATIO = 1e-8  # smallest/largest spread of a neighbourhood below which it has no 3D frame
STRETCH_GUARD = 1e-12  # below this skew (|d x u|) the minimal stretch is the identity
POINT_REFLECTION_ANGLE = 1e-3  # radians; an articulated fit this close to a point reflection has no axis


@dataclasses.dataclass(frozen=True)
class LocalSymmetries:
    """Per-pair output of Step 1; every array has a leading axis of n pairs.

    normals (n, 3): local mirror normals, pointing from the left to the right side.
    left_transforms, right_transforms (n, 3, 3): M_p and M_q.
    gap_transforms (n, 3, 3): applied to p_i - q_j in the alpha terms of Step 2.
    residuals (n,): relative RMS mirror residual of each transformed neighbourhood.
    pair_misfits (n,): the pair's own mirror residual / the neighbourhood RMS radius
        (about 2 for a landmark paired with the wrong vertex, below 0.5 on sound inputs).
    stretch (n,): the stretch factor s of S (1 where no stretch is applied).
    point_reflections (n,) bool: articulated fits that fell back to identity.
    """

    normals: np.ndarray
    left_transforms: np.ndarray
    right_transforms: np.ndarray
    gap_transforms: np.ndarray
    residuals: np.ndarray
    pair_misfits: np.ndarray
    stretch: np.ndarray
    point_reflections: np.ndarray

    def rotated(self, rotation: np.ndarray) -> LocalSymmetries:
        """The same local symmetries in a frame rotated by ``rotation`` (3, 3) (Step 2 solves in the frame
        whose x axis is the first pair's mirror normal)."""

        def conjugated(m):
            return rotation @ m @ rotation.T

        return dataclasses.replace(
            self, normals=self.normals @ rotation.T, left_transforms=conjugated(self.left_transforms),
            right_transforms=conjugated(self.right_transforms), gap_transforms=conjugated(self.gap_transforms))


@dataclasses.dataclass(frozen=True)
class _Moments:
    """theta-weighted sums over each neighbourhood: weight w (n,), centroids, second moments."""

    weight: np.ndarray
    left_mean: np.ndarray
    right_mean: np.ndarray
    left_left: np.ndarray  # sum theta p p^T (n, 3, 3)
    right_right: np.ndarray
    left_right: np.ndarray  # sum theta p q^T
    flat: np.ndarray | None = None  # the unit normal of a flat (2D) input's plane

    def centred(self, left_centre: np.ndarray, right_centre: np.ndarray):
        """Second moments about per-pair centres: (Cpp, Cqq, Kpq) each (n, 3, 3).

        For a flat input every moment is zero along the plane's normal, which no model can tell from
        a mirror direction. There the moments get a spread along the normal as large as the mean one
        in the plane, the same on both sides (a mirror across a line of the plane leaves the normal
        as it is): the local normals then lie in the plane, the stretch stays in it, and a rotation
        between the sides is one about the normal, which in 2D is a turned mirror line."""
        w = self.weight[:, None, None]
        sl = self.left_mean * self.weight[:, None]
        sr = self.right_mean * self.weight[:, None]

        def about(total, a_sum, b_sum, a_centre, b_centre):
            return (total - a_centre[:, :, None] * b_sum[:, None, :]
                    - a_sum[:, :, None] * b_centre[:, None, :]
                    + w * a_centre[:, :, None] * b_centre[:, None, :])

        moments = (about(self.left_left, sl, sl, left_centre, left_centre),
                   about(self.right_right, sr, sr, right_centre, right_centre),
                   about(self.left_right, sl, sr, left_centre, right_centre))
        if self.flat is None:
            return moments
        spread = 0.25 * (np.trace(moments[0], axis1=1, axis2=2) + np.trace(moments[1], axis1=1, axis2=2))
        normal = spread[:, None, None] * np.outer(self.flat, self.flat)
        return tuple(moment + normal for moment in moments)


def _moments(theta: sp.csr_matrix, left: np.ndarray, right: np.ndarray, flat: np.ndarray | None) -> _Moments:
    n = len(left)

    def outer(a, b):
        return (a[:, :, None] * b[:, None, :]).reshape(n, 9)

    sums = theta @ np.hstack(
        [np.ones((n, 1)), left, right, outer(left, left), outer(right, right), outer(left, right)]
    )
    w = sums[:, 0]
    return _Moments(
        w, sums[:, 1:4] / w[:, None], sums[:, 4:7] / w[:, None],
        sums[:, 7:16].reshape(n, 3, 3), sums[:, 16:25].reshape(n, 3, 3),
        sums[:, 25:34].reshape(n, 3, 3), flat,
    )


def _smallest_eigenvector(symmetric: np.ndarray) -> np.ndarray:
    return np.linalg.eigh(symmetric)[1][:, :, 0]


def _symmetrize(m: np.ndarray) -> np.ndarray:
    return m + np.swapaxes(m, 1, 2)


def _fit_quality(moments, left, right, centres, normals, transforms):
    """Mirror residuals after the local transform, relative to the neighbourhood's RMS radius.

    Returns (neighbourhood (n,), pair (n,)): the RMS of |M_p p' - U M_q q'| over
    the theta-weighted neighbourhood, and the same for the pair's own landmarks,
    where U mirrors across n_i and p', q' are taken about the local ``centres`` (left (n, 3), right
    (n, 3)); ``transforms``: (M_p, M_q), each (n, 3, 3).
    """
    (left_centre, right_centre), (m_left, m_right) = centres, transforms
    cpp, cqq, kpq = moments.centred(left_centre, right_centre)
    mirror = np.eye(3) - 2.0 * normals[:, :, None] * normals[:, None, :]
    gram_l = np.swapaxes(m_left, 1, 2) @ m_left
    gram_r = np.swapaxes(m_right, 1, 2) @ m_right
    spread = np.einsum("nij,nji->n", gram_l, cpp) + np.einsum("nij,nji->n", gram_r, cqq)
    cross = np.einsum("nij,nij->n", np.swapaxes(m_left, 1, 2) @ mirror @ m_right, kpq)
    neighbourhood = np.sqrt(np.clip(spread - 2.0 * cross, 0.0, None) / spread)
    own = (np.einsum("nij,nj->ni", m_left, left - left_centre)
           - np.einsum("nij,nj->ni", mirror @ m_right, right - right_centre))
    radius = np.sqrt(0.5 * spread / moments.weight)
    return neighbourhood, np.linalg.norm(own, axis=1) / radius


def _degenerate(pair_ids: np.ndarray, mask: np.ndarray, layout: str, estimate: str, fix: str):
    return DegenerateNeighbourhoodError(
        f"The landmarks around pair(s) {id_list(pair_ids[mask])} are (nearly) {layout}, so the "
        f"{estimate} cannot be estimated there. {fix} A pair far from its neighbours' partners "
        "is cut off from them and causes this too: check that it joins the right two vertices.",
        pair_ids[mask],
    )


def _standard(moments: _Moments, pair_ids: np.ndarray | None = None):
    centre = 0.5 * (moments.left_mean + moments.right_mean)
    _, _, kpq = moments.centred(centre, centre)
    normals = _smallest_eigenvector(_symmetrize(kpq))
    identity = np.broadcast_to(np.eye(3), (len(normals), 3, 3))
    none = np.zeros(len(normals), dtype=bool)
    return normals, identity, identity, identity, centre, centre, np.ones(len(normals)), none


def _affine(moments: _Moments, pair_ids: np.ndarray):
    centre = 0.5 * (moments.left_mean + moments.right_mean)
    cpp, cqq, kpq = moments.centred(centre, centre)
    spread, frames = np.linalg.eigh(cpp + cqq)
    flat = spread[:, 0] <= DEGENERATE_RATIO * spread[:, 2]
    if flat.any():
        raise _degenerate(pair_ids, flat, "coplanar", "local stretch (affine mode)",
                          "Increase `theta_width`, add landmarks off that plane, or use mode='standard'.")
    root = np.sqrt(spread)
    isotropic = (frames / root[:, None, :]) @ np.swapaxes(frames, 1, 2)  # T = C^-1/2
    inverse = (frames * root[:, None, :]) @ np.swapaxes(frames, 1, 2)  # T^-1
    plane_normal = _smallest_eigenvector(_symmetrize(isotropic @ kpq @ isotropic))
    u = normalize(np.einsum("nij,nj->ni", isotropic, plane_normal))  # normal of H*
    d = normalize(np.einsum("nij,nj->ni", inverse, plane_normal))  # skew mirror direction n*
    u *= np.where(np.einsum("ni,ni->n", d, u) < 0, -1.0, 1.0)[:, None]
    cos = np.einsum("ni,ni->n", d, u)
    sin = np.linalg.norm(np.cross(d, u), axis=1)
    skewed = sin > STRETCH_GUARD
    m = normalize(d - cos[:, None] * u)  # normalized projection of n* onto H*
    v = normalize(d - m)
    stretch = np.where(skewed, (1.0 + sin) / cos, 1.0)
    s_matrix = np.eye(3) + (stretch - 1.0)[:, None, None] * v[:, :, None] * v[:, None, :]
    normals = normalize(np.einsum("nij,nj->ni", s_matrix, d))
    return (normals, s_matrix, s_matrix, s_matrix, centre, centre, stretch,
            np.zeros(len(normals), dtype=bool))


def _articulated(moments: _Moments, pair_ids: np.ndarray):
    n = len(moments.weight)
    _, _, kpq = moments.centred(moments.left_mean, moments.right_mean)
    singular = np.linalg.svd(kpq, compute_uv=False)
    collinear = singular[:, 1] <= DEGENERATE_RATIO * singular[:, 0]
    if collinear.any():
        raise _degenerate(pair_ids, collinear, "collinear", "local rotation (articulated mode)",
                          "Increase `theta_width` or add landmarks off that line.")
    rotation = proper_rotation_fit(-kpq)  # V with p' ~ V(-q')
    skew = np.stack([rotation[:, 2, 1] - rotation[:, 1, 2], rotation[:, 0, 2] - rotation[:, 2, 0],
                     rotation[:, 1, 0] - rotation[:, 0, 1]], axis=1)  # 2 sin(angle) axis
    # atan2, not arccos: theta ~ pi is the common (already symmetric) case, where
    # arccos of the trace loses half the digits.
    angle = np.arctan2(0.5 * np.linalg.norm(skew, axis=1),
                       0.5 * (np.trace(rotation, axis1=1, axis2=2) - 1.0))
    # The axis from the symmetric part: the skew part vanishes at theta = pi.
    axis = np.linalg.eigh(_symmetrize(rotation))[1][:, :, -1]
    axis *= np.where(np.einsum("ni,ni->n", axis, skew) < 0, -1.0, 1.0)[:, None]
    point_reflection = angle < POINT_REFLECTION_ANGLE
    half_turn = np.where(point_reflection, 0.0, 0.5 * (angle - np.pi))
    z = rotation_about_axis(axis, half_turn)
    normals = axis
    if point_reflection.any():
        standard_normals = _standard(moments)[0]
        normals = np.where(point_reflection[:, None], standard_normals, axis)
    identity = np.broadcast_to(np.eye(3), (n, 3, 3))
    return (normals, np.swapaxes(z, 1, 2), z, identity, moments.left_mean,
            moments.right_mean, np.ones(n), point_reflection)


MODELS = {"standard": _standard, "affine": _affine, "articulated": _articulated}


def local_symmetries(
    mode: str, theta: sp.csr_matrix, left: np.ndarray, right: np.ndarray, pair_ids: np.ndarray,
    flat: np.ndarray | None = None,
) -> LocalSymmetries:
    """Step 1 for every pair at once.

    mode: "standard" | "affine" | "articulated". theta (n, n): neighbourhood
    weights. left, right (n, 3): pair positions. pair_ids (n,): labels for messages.
    flat (3,): the unit normal of the plane holding a flat (2D) input, None otherwise.
    """
    moments = _moments(theta, left, right, flat)
    normals, m_left, m_right, m_gap, left_centre, right_centre, stretch, point_refl = MODELS[mode](
        moments, pair_ids)
    transformed_gap = (np.einsum("nij,nj->ni", m_right, moments.right_mean)
                       - np.einsum("nij,nj->ni", m_left, moments.left_mean))
    normals = normals * np.where(np.einsum("ni,ni->n", normals, transformed_gap) < 0,
                                 -1.0, 1.0)[:, None]
    residuals, misfits = _fit_quality(moments, left, right, (left_centre, right_centre), normals,
                                      (m_left, m_right))
    return LocalSymmetries(normals, np.ascontiguousarray(m_left), np.ascontiguousarray(m_right),
                           np.ascontiguousarray(m_gap), residuals, misfits, stretch, point_refl)
