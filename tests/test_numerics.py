"""Step 1, Step 2 and the warp against closed-form truths and independent computations."""

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.interpolate import RBFInterpolator
from scipy.sparse.csgraph import connected_components
from scipy.spatial.distance import cdist

from filter_symblend.core.geometry import MIRROR_X, minimal_rotation, rotation_about_axis
from filter_symblend.core.global_solve import MINUS_X, global_solve
from filter_symblend.core.local_symmetries import local_symmetries
from filter_symblend.core.neighbourhoods import _symmetric, pair_weights, pair_weights_at
from filter_symblend.core.warp import choice, iterative, splines
from filter_symblend.errors import SymblendWarning
from filter_symblend.testing import synthetic

MODES = ["standard", "affine", "articulated"]


def symmetric_pairs(n=40, seed=0):
    rng = np.random.default_rng(seed)
    left = rng.normal(size=(n, 3))
    left[:, 0] = np.abs(left[:, 0]) + 0.3
    return left, left @ MIRROR_X


def full_weights(n):
    return sp.csr_matrix(np.ones((n, n)))


def mirror_residual(left, right, normal):
    """max |left - mirror(right)| across the plane with ``normal`` through the centroid."""
    centre = 0.5 * (left.mean(axis=0) + right.mean(axis=0))
    mirrored = right - 2.0 * ((right - centre) @ normal)[:, None] * normal
    return np.abs(left - mirrored).max()


@pytest.mark.parametrize("mode", MODES)
def test_symmetric_neighbourhood_needs_no_transform(mode):
    p, q = symmetric_pairs()
    local = local_symmetries(mode, full_weights(len(p)), p, q, np.arange(1, len(p) + 1))
    np.testing.assert_allclose(local.left_transforms, np.broadcast_to(np.eye(3), (len(p), 3, 3)), atol=1e-12)
    np.testing.assert_allclose(local.right_transforms, local.left_transforms, atol=1e-12)
    np.testing.assert_allclose(local.normals, np.broadcast_to(MINUS_X, (len(p), 3)), atol=1e-12)


def test_affine_stretch_makes_an_affine_image_exactly_symmetric():
    p0, q0 = symmetric_pairs()
    rng = np.random.default_rng(3)
    for _ in range(20):
        a = np.eye(3) + 0.3 * rng.normal(size=(3, 3))
        p, q = p0 @ a.T, q0 @ a.T
        local = local_symmetries("affine", full_weights(len(p)), p, q, np.arange(1, len(p) + 1))
        s = local.left_transforms[0]
        assert mirror_residual(p @ s.T, q @ s.T, local.normals[0]) < 1e-12
        # the skew mirror direction recovered is A n0
        direction = np.linalg.solve(s, local.normals[0])
        np.testing.assert_allclose(np.cross(direction / np.linalg.norm(direction),
                                            a @ MINUS_X / np.linalg.norm(a @ MINUS_X)), 0, atol=1e-10)


def test_minimal_stretch_equals_a_pure_oblique_compression():
    p0, q0 = symmetric_pairs()
    d = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    compression = np.eye(3) - 0.4 * np.outer(d, d)
    local = local_symmetries("affine", full_weights(len(p0)), p0 @ compression.T, q0 @ compression.T,
                             np.arange(1, len(p0) + 1))
    assert local.stretch[0] == pytest.approx(1 / 0.6, rel=1e-12)


def test_articulated_rotation_undoes_a_rigidly_turned_side():
    p, q0 = symmetric_pairs()
    turn = rotation_about_axis(np.array([[0.0, 0.6, 0.8]]), np.array([0.7]))[0]
    q = (q0 - q0.mean(axis=0)) @ turn.T + q0.mean(axis=0) + [0.1, 0.2, -0.3]
    local = local_symmetries("articulated", full_weights(len(p)), p, q, np.arange(1, len(p) + 1))
    z_left, z_right, axis = local.left_transforms[0], local.right_transforms[0], local.normals[0]
    pc, qc = p - p.mean(axis=0), q - q.mean(axis=0)
    mirror = np.eye(3) - 2 * np.outer(axis, axis)
    np.testing.assert_allclose(pc @ z_left.T, qc @ z_right.T @ mirror.T, atol=1e-12)
    np.testing.assert_allclose(z_left, z_right.T, atol=1e-15)
    # minimal: each side turns by half the relative rotation (0.7 rad) at most
    angle = np.arccos(np.clip((np.trace(z_right) - 1) / 2, -1, 1))
    assert angle <= 0.5 * np.pi


def test_normals_point_from_left_to_right_in_any_pose():
    p, q = symmetric_pairs()
    turn = rotation_about_axis(np.array([[0.3, 0.9, 0.3]]) / np.linalg.norm([0.3, 0.9, 0.3]), np.array([2.5]))[0]
    for mode in MODES:
        local = local_symmetries(mode, full_weights(len(p)), p @ turn.T, q @ turn.T, np.arange(1, len(p) + 1))
        np.testing.assert_allclose(local.normals, np.broadcast_to(turn @ MINUS_X, local.normals.shape), atol=1e-10)


def test_minimal_rotation_is_smallest_and_handles_the_opposite_vector():
    rng = np.random.default_rng(0)
    sources = rng.normal(size=(50, 3))
    sources /= np.linalg.norm(sources, axis=1, keepdims=True)
    sources[0] = -MINUS_X
    rotations = minimal_rotation(sources, MINUS_X)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", rotations, sources), np.broadcast_to(MINUS_X, (50, 3)), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(rotations), 1.0)
    angles = np.arccos(np.clip((np.trace(rotations, axis1=1, axis2=2) - 1) / 2, -1, 1))
    np.testing.assert_allclose(angles, np.arccos(np.clip(sources @ MINUS_X, -1, 1)), atol=1e-7)


def dense_least_squares(phi, p, q, local, alpha, wl=None, wr=None, on_plane=None):
    """The paper's functional (with K in the alpha terms and per-landmark weights), solved as a
    dense least-squares problem; midline pairs have their x column removed (x = 0)."""
    n = len(p)
    wl = np.ones(n) if wl is None else wl
    wr = np.ones(n) if wr is None else wr
    rot = minimal_rotation(local.normals, MINUS_X)
    rows, rhs = [], []
    mirror = np.diag([-1.0, 1.0, 1.0])

    def block(i_coeff, j_coeff, i, j, target, weight):
        row = np.zeros((3, 3 * n))
        row[:, 3 * i:3 * i + 3] += i_coeff
        row[:, 3 * j:3 * j + 3] -= j_coeff
        rows.append(np.sqrt(weight) * row)
        rhs.append(np.sqrt(weight) * target)

    dense = phi.toarray()
    for i in range(n):
        a_p, a_q, a_g = rot[i] @ local.left_transforms[i], rot[i] @ local.right_transforms[i], rot[i] @ local.gap_transforms[i]
        for j in range(n):
            w = dense[i, j]
            if w == 0:
                continue
            block(np.eye(3), np.eye(3), i, j, a_p @ (p[i] - p[j]), w * wl[i] * wl[j])
            block(mirror, mirror, i, j, a_q @ (q[i] - q[j]), w * wr[i] * wr[j])
            block(np.eye(3), mirror, i, j, a_g @ (p[i] - q[j]), alpha * w * wl[i] * wr[j])
            block(mirror, np.eye(3), i, j, a_g @ (q[i] - p[j]), alpha * w * wr[i] * wl[j])
    matrix = np.vstack(rows)
    keep = np.ones(3 * n, dtype=bool)
    if on_plane is not None:
        keep[3 * np.flatnonzero(on_plane)] = False
    solution = np.zeros(3 * n)
    solution[keep] = np.linalg.lstsq(matrix[:, keep], np.concatenate(rhs), rcond=None)[0]
    return solution.reshape(n, 3)


@pytest.mark.parametrize("mode", MODES)
def test_global_solve_matches_dense_least_squares_of_the_functional(mode):
    rng = np.random.default_rng(5)
    p, q = symmetric_pairs(25, seed=2)
    p = p + 0.2 * rng.normal(size=p.shape)
    q = q + 0.2 * rng.normal(size=q.shape)
    phi = pair_weights(p, q, 1.0)
    local = local_symmetries(mode, pair_weights(p, q, 1.5), p, q, np.arange(1, 26))
    r, s = global_solve(phi, p, q, local, alpha=0.05)
    np.testing.assert_allclose(r, dense_least_squares(phi, p, q, local, 0.05), atol=1e-10)
    np.testing.assert_allclose(s, r * [-1, 1, 1])


def test_weighted_solve_with_midline_matches_dense_least_squares():
    rng = np.random.default_rng(9)
    p, q = symmetric_pairs(25, seed=3)
    p, q = p + 0.2 * rng.normal(size=p.shape), q + 0.2 * rng.normal(size=q.shape)
    q[:3] = p[:3] = p[:3] * [0.0, 1.0, 1.0]  # three midline landmarks: left = right
    on_plane = np.arange(25) < 3
    wl, wr = rng.uniform(0.2, 1.0, 25), rng.uniform(0.2, 1.0, 25)
    wr[5], wl[8] = 0.0, 0.0
    phi = pair_weights(p, q, 1.0)
    local = local_symmetries("affine", pair_weights(p, q, 1.5), p, q, np.arange(1, 26))
    r, s = global_solve(phi, p, q, local, alpha=0.05, weights=(wl, wr), on_plane=on_plane)
    expected = dense_least_squares(phi, p, q, local, 0.05, wl, wr, on_plane)
    expected[:, 1:] -= expected[:, 1:].mean(axis=0)
    np.testing.assert_allclose(r, expected, atol=1e-10)
    assert np.all(r[on_plane, 0] == 0.0)


def test_global_solve_reproduces_a_globally_affine_input_exactly():
    p0, q0 = symmetric_pairs(30)
    a = np.array([[0.6, 0.3, 0.1], [0.2, 1.1, -0.2], [0.1, 0.0, 0.9]])
    p, q = p0 @ a.T, q0 @ a.T
    phi = pair_weights(p, q, 1.0)
    local = local_symmetries("affine", pair_weights(p, q, 2.0), p, q, np.arange(1, 31))
    frame = minimal_rotation(local.normals[:1], MINUS_X)[0]
    s_matrix = local.left_transforms[0]
    r, s = global_solve(phi, p @ frame.T, q @ frame.T, local.rotated(frame), alpha=0.01)
    expected = np.vstack([p, q]) @ (frame @ s_matrix).T
    expected -= expected.mean(axis=0) * [0, 1, 1]
    np.testing.assert_allclose(np.vstack([r, s]), expected, atol=1e-12)


@pytest.mark.parametrize("kind", ["exact", "iterative", "approximate"])
def test_thin_plate_spline_is_exact_at_landmarks_and_reproduces_affine_maps(monkeypatch, kind):
    if kind != "exact":
        monkeypatch.setattr(choice, "EXACT_CENTRES", 50)
        monkeypatch.setattr(choice, "ITERATIVE_CENTRES", 50 if kind == "approximate" else 10_000)
        monkeypatch.setattr(splines, "SUBSET_CENTRES", 40)
        monkeypatch.setattr(iterative, "COARSE_CENTRES", 40)
        monkeypatch.setattr(iterative, "CENTRES_PER_PATCH", 20)
    rng = np.random.default_rng(1)
    source = rng.normal(size=(200, 3))
    displacement = 0.1 * rng.normal(size=source.shape)
    spline = choice.thin_plate_spline(source, displacement)
    assert isinstance(spline, splines.ApproximateThinPlateSpline) == (kind == "approximate")
    assert ("solved iteratively" in spline.description) == (kind == "iterative")
    scale = np.ptp(source, axis=0).max()
    np.testing.assert_allclose(spline(source), displacement, atol=1e-10 if kind != "iterative" else
                               iterative.TOLERANCE * scale)
    a = np.eye(3) + 0.2 * rng.normal(size=(3, 3))
    points = rng.normal(size=(500, 3))
    affine = choice.thin_plate_spline(source, source @ a.T + 1.5 - source)
    np.testing.assert_allclose(points + affine(points), points @ a.T + 1.5, atol=1e-10)


def test_the_hand_written_spline_equals_scipys_rbf_interpolator():
    """Blocked evaluation from expanded squared distances, near-landmark vertices re-evaluated:
    the same values as RBFInterpolator(kernel="linear", degree=1), far from the origin too."""
    rng = np.random.default_rng(2)
    centres = 1000.0 + 50.0 * rng.normal(size=(700, 3))
    values = rng.normal(size=(700, 3))
    points = np.vstack([1000.0 + 60.0 * rng.normal(size=(3000, 3)), centres[:5] + 1e-9, centres[5:10]])
    expected = RBFInterpolator(centres, values, kernel="linear", degree=1)(points)
    progress = []
    ours = splines.ThinPlateSpline(centres, values)(points, progress.append)
    np.testing.assert_allclose(ours, expected, rtol=0, atol=1e-9 * np.abs(expected).max())
    assert progress[-1] == 1.0 and all(b - a >= 0.05 for a, b in zip(progress, progress[1:-1]))
    few = points[[0, 3000, 3007]]  # a few points (a centre, within 1e-9 of one, another centre): computed directly
    assert len(few) * len(centres) <= splines.DIRECT_ELEMENTS
    np.testing.assert_allclose(splines.ThinPlateSpline(centres, values)(few), expected[[0, 3000, 3007]], rtol=0,
                               atol=1e-9 * np.abs(expected).max())


@pytest.mark.parametrize("parallel", [True, False])
def test_vertices_that_are_landmarks_are_evaluated_exactly_block_by_block(parallel):
    """Every landmark a vertex (as with dense automatic pairs), and as many vertices within 1e-9 of one: all of
    them near a landmark, re-evaluated from coordinate differences in many blocks, on the cores or not; the
    same values as scipy's direct sum, and the landmarks' own values."""
    from scipy.spatial.distance import cdist
    rng = np.random.default_rng(5)
    centres = rng.normal(size=(3000, 3))
    values = rng.normal(size=(3000, 3))
    points = np.vstack([centres, centres + 1e-9])
    spline = splines.ThinPlateSpline(centres, values)
    assert len(points) > 10 * (splines.BLOCK_ELEMENTS // len(centres))  # many blocks
    ours = spline(points, parallel=parallel)
    scaled = (points - spline._shift) / spline._scale
    distances = cdist(scaled, spline._centres)
    direct = spline._polynomial_part(scaled) - distances @ spline._weights
    terms = (distances @ np.abs(spline._weights)).max()  # the sum's rounding: its terms' size, not its own
    np.testing.assert_allclose(ours, direct, rtol=0, atol=1e-14 * terms)
    np.testing.assert_allclose(ours[:3000], values, rtol=0, atol=1e-14 * terms)


def test_the_approximate_spline_stays_close_to_the_exact_one_on_a_smooth_map(monkeypatch):
    """Many landmarks of a smooth deformation: the approximation (exact spline through a
    farthest-point subset plus local splines of the residual on patches) is exact at every landmark and within
    0.1 % of the displacement of the exact spline everywhere."""
    monkeypatch.setattr(choice, "EXACT_CENTRES", 500)
    monkeypatch.setattr(choice, "ITERATIVE_CENTRES", 500)
    monkeypatch.setattr(splines, "SUBSET_CENTRES", 300)
    rng = np.random.default_rng(3)
    centres = rng.uniform(-1, 1, size=(1200, 3))
    centres /= np.linalg.norm(centres, axis=1, keepdims=True)  # on the unit sphere, like a surface
    def bend(x):
        return np.column_stack([0.3 * np.sin(2 * x[:, 1]), 0.2 * x[:, 0] * x[:, 2], 0.1 * np.cos(3 * x[:, 0])])
    points = rng.normal(size=(4000, 3))
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    approximate = choice.thin_plate_spline(centres, bend(centres))
    exact = splines.ThinPlateSpline(centres, bend(centres))(points)
    assert approximate.description.startswith("thin-plate spline through 300 of the 1200 landmarks")
    np.testing.assert_allclose(approximate(centres), bend(centres), atol=1e-10)
    assert np.abs(approximate(points) - exact).max() < 1e-3 * np.abs(exact).max()  # measured 2.8e-5


def test_iterative_solve_equals_the_dense_one(monkeypatch):
    """The conjugate-gradient path (large sparse systems) gives the dense Cholesky answer."""
    import filter_symblend.core.global_solve as solve_module

    rng = np.random.default_rng(4)
    p, q = symmetric_pairs(300, seed=6)
    p, q = p + 0.05 * rng.normal(size=p.shape), q + 0.05 * rng.normal(size=q.shape)
    phi = pair_weights(p, q, 0.5)  # connected, a third of the pairs linked
    assert connected_components(phi)[0] == 1
    local = local_symmetries("affine", pair_weights(p, q, 0.8), p, q, np.arange(1, 301))
    dense = global_solve(phi, p, q, local, alpha=0.01)
    monkeypatch.setattr(solve_module, "DENSE_SIZE", 10)
    monkeypatch.setattr(solve_module, "DENSE_FRACTION", 1.1)
    from threadpoolctl import threadpool_info
    blas_threads = [library["num_threads"] for library in threadpool_info()]
    iterative = global_solve(phi, p, q, local, alpha=0.01)  # x and y/z side by side, products in threads
    assert phi.nnz < 0.5 * 300 * 300, "the test must exercise a sparse system"
    np.testing.assert_allclose(iterative[0], dense[0], atol=1e-10)
    assert [library["num_threads"] for library in threadpool_info()] == blas_threads  # BLAS threads restored


def test_a_solve_that_does_not_converge_says_so(monkeypatch):
    import filter_symblend.core.global_solve as solve_module
    from filter_symblend import GeometryError

    p, q = symmetric_pairs(300, seed=6)
    phi = pair_weights(p, q, 0.5)
    local = local_symmetries("standard", phi, p, q, np.arange(1, 301))
    monkeypatch.setattr(solve_module, "DENSE_SIZE", 10)
    monkeypatch.setattr(solve_module, "DENSE_FRACTION", 1.1)
    monkeypatch.setattr(solve_module, "CG_MAX_ITERATIONS", 2)
    with pytest.raises(GeometryError, match=r"did not converge in 2 iterations; lower `phi_width`"):
        global_solve(phi, p + 0.1, q, local, alpha=0.01)


def _iterative_against_dense(monkeypatch, centres, values, points):
    """(iterative spline, largest |iterative - dense| at ``points`` relative to the landmarks' extent), with a
    coarse level much smaller than the landmarks so that the iteration has work to do."""
    monkeypatch.setattr(iterative, "COARSE_CENTRES", len(centres) // 8)
    monkeypatch.setattr(iterative, "CENTRES_PER_PATCH", 50)
    refined = iterative.iterative_thin_plate_spline(centres, values)
    dense = splines.ThinPlateSpline(centres, values)
    return refined, np.abs(refined(points) - dense(points)).max() / np.ptp(centres, axis=0).max()


@pytest.mark.parametrize("roughness", [0.0, 1.0])
def test_the_iterative_spline_is_the_dense_one(monkeypatch, roughness):
    """Landmarks on a sphere, a smooth map plus (second case) noise as large as the map: the refined spline
    equals the dense LU's at points all around, to the iteration's tolerance, in several steps."""
    rng = np.random.default_rng(7)
    centres = rng.normal(size=(1600, 3))
    centres /= np.linalg.norm(centres, axis=1, keepdims=True)
    values = np.column_stack([0.3 * np.sin(2 * centres[:, 1]), 0.2 * centres[:, 0] * centres[:, 2],
                              0.1 * np.cos(3 * centres[:, 0])]) + roughness * 0.1 * rng.normal(size=centres.shape)
    points = 1.2 * rng.uniform(-1, 1, size=(3000, 3))
    refined, deviation = _iterative_against_dense(monkeypatch, centres, values, points)
    assert refined.residual <= iterative.TOLERANCE
    assert deviation < 10 * iterative.TOLERANCE
    assert 1 < refined.steps < iterative.MAX_STEPS
    assert f"({refined.steps} steps, largest residual" in refined.description


def test_the_minimal_residual_iteration_needs_no_more_steps_than_plain_refinement(monkeypatch):
    """The same preconditioner in a plain refinement (w += M(r) projected, the affine part refitted each step),
    written out here, on a rough map: after as many steps its residual is no smaller than the solver's, and it
    reaches the tolerance no sooner."""
    rng = np.random.default_rng(7)
    centres = rng.normal(size=(1600, 3))
    centres /= np.linalg.norm(centres, axis=1, keepdims=True)
    values = np.sin(3 * centres) + 0.1 * rng.normal(size=centres.shape)
    refined, _ = _iterative_against_dense(monkeypatch, centres, values, centres)
    scale = np.ptp(centres, axis=0).max()
    scaled = (centres - centres.mean(axis=0)) / scale
    affine = np.column_stack([np.ones(len(scaled)), scaled])
    basis = np.linalg.qr(affine)[0]
    precondition = iterative._Preconditioner(scaled)
    weights, residual, misfits = np.zeros_like(values), values, []
    for _ in range(refined.steps + 3):
        change = precondition(residual)
        weights += change - basis @ (basis.T @ change)
        kernel_part = -cdist(scaled, scaled) @ weights
        residual = values - kernel_part
        residual -= basis @ (basis.T @ residual)
        misfits.append(np.abs(residual).max() / scale)
    assert refined.residual <= misfits[refined.steps - 1]
    assert min(misfits) <= iterative.TOLERANCE  # the plain refinement converges too, only later or as fast
    assert refined.steps <= next(step for step, misfit in enumerate(misfits, 1) if misfit <= iterative.TOLERANCE)


def test_the_iterative_spline_handles_flat_patches(monkeypatch):
    """Landmarks on the faces of a cube (every patch inside a face is planar): still the dense spline."""
    rng = np.random.default_rng(8)
    centres = rng.uniform(-1, 1, size=(1600, 3))
    axis = rng.integers(0, 3, size=len(centres))
    centres[np.arange(len(centres)), axis] = rng.choice([-1.0, 1.0], size=len(centres))
    values = np.column_stack([np.sin(centres[:, 1]), centres[:, 0] * centres[:, 2], np.cos(centres[:, 0])])
    refined, deviation = _iterative_against_dense(monkeypatch, centres, values, rng.uniform(-1, 1, size=(2000, 3)))
    assert refined.residual <= iterative.TOLERANCE and deviation < 10 * iterative.TOLERANCE


def test_an_iteration_stopped_short_says_so(monkeypatch):
    monkeypatch.setattr(iterative, "MAX_STEPS", 1)
    rng = np.random.default_rng(9)
    centres = rng.normal(size=(800, 3))
    values = 0.1 * rng.normal(size=centres.shape)
    monkeypatch.setattr(iterative, "COARSE_CENTRES", 50)
    with pytest.warns(SymblendWarning, match=r"warp's iterative solve stopped after 1 step at a residual of "
                                             r"[0-9.e+-]+ of the landmarks' extent"):
        iterative.iterative_thin_plate_spline(centres, values)


def test_the_approximate_spline_handles_flat_patches(monkeypatch):
    """Landmarks on the faces of a cube: every correction patch inside a face is planar, where a
    local spline with an affine part would be singular; the constant part keeps it solvable."""
    monkeypatch.setattr(choice, "EXACT_CENTRES", 500)
    monkeypatch.setattr(choice, "ITERATIVE_CENTRES", 500)
    monkeypatch.setattr(splines, "SUBSET_CENTRES", 200)
    rng = np.random.default_rng(5)
    centres = rng.uniform(-1, 1, size=(1500, 3))
    axis = rng.integers(0, 3, size=len(centres))
    centres[np.arange(len(centres)), axis] = rng.choice([-1.0, 1.0], size=len(centres))  # onto a face
    values = np.column_stack([np.sin(centres[:, 1]), centres[:, 0] * centres[:, 2], np.cos(centres[:, 0])])
    approximate = choice.thin_plate_spline(centres, values)
    np.testing.assert_allclose(approximate(centres), values, atol=1e-9)
    points = rng.uniform(-1, 1, size=(2000, 3))
    exact = splines.ThinPlateSpline(centres, values)(points)
    assert np.isfinite(approximate(points)).all()
    assert np.abs(approximate(points) - exact).max() < 0.03 * np.abs(exact).max()  # measured 0.013 (inside the cube)


def test_farthest_point_order_matches_the_textbook_loop():
    """The per-axis, squared-distance sampler picks the same points in the same order as the
    plain loop over Euclidean norms (it is 10x faster at 40k points x 6,000 picks)."""
    from filter_symblend.core.mesh_quantities import farthest_point_order

    points = np.random.default_rng(8).normal(size=(3000, 3))
    distance, expected = np.linalg.norm(points - points[7], axis=1), [7]
    for _ in range(199):
        expected.append(int(np.argmax(distance)))
        distance = np.minimum(distance, np.linalg.norm(points - points[expected[-1]], axis=1))
    np.testing.assert_array_equal(farthest_point_order(points, 200, start=7), expected)
    assert farthest_point_order(points[:0], 0).shape == (0,)  # none among none (every twin of a shape confident)


@pytest.mark.parametrize("count", [5, 300, 3001])
def test_the_spline_at_its_own_centres_equals_the_direct_sum(count):
    """The refinement's product K w computes each distance between two centres once for both; against the
    direct sum from scipy's cdist, with two centres 1e-9 apart (evaluated from coordinate differences)."""
    from scipy.spatial.distance import cdist
    rng = np.random.default_rng(count)
    centres = rng.normal(size=(count, 3))
    centres[1] = centres[0] + 1e-9
    weights, polynomial = rng.normal(size=(count, 3)), rng.normal(size=(4, 3))
    spline = splines.ThinPlateSpline.from_coefficients(centres, np.zeros(3), 1.0, weights, polynomial, "")
    direct = np.column_stack([np.ones(count), centres]) @ polynomial - cdist(centres, centres) @ weights
    np.testing.assert_allclose(spline.at_centres(), direct, rtol=0, atol=1e-12 * np.abs(direct).max())


def test_the_accelerated_mirror_plane_icp_reaches_the_converged_plane(cow, monkeypatch):
    """Reflection ICP (core/mirror_planes) from a plane 10 degrees off: on the exactly symmetric cow in a random
    pose it ends on the true plane; on the cow bent 1.0 rad (no plane mirrors it) it ends no worse than plain ICP
    capped at 40 steps, nor than plain ICP run to 200 steps (0.1 % leeway; measured 0.0399 against 0.0456 and
    0.0456: the plain steps settle in a worse plane from this start)."""
    from scipy.spatial import cKDTree

    from filter_symblend.core import mirror_planes
    from filter_symblend.core.geometry import normalize
    from filter_symblend.core.mesh_quantities import evenly

    def tilted(normal):
        axis = normalize(np.cross(normal, [0.3, 0.5, 0.8]))
        return normal * np.cos(np.radians(10)) + np.cross(axis, normal) * np.sin(np.radians(10))

    posed = synthetic.random_rigid(cow.points, seed=5)
    rotation = np.linalg.lstsq(np.column_stack([cow.points, np.ones(len(posed))]), posed, rcond=None)[0][:3].T
    true_normal = rotation @ [1.0, 0.0, 0.0]
    true_offset = float(true_normal @ posed[cow.all_left[0]] + true_normal @ posed[cow.all_right[0]]) / 2
    sample = evenly(posed, mirror_planes.ICP_SAMPLES)
    normal, offset, _ = mirror_planes._refine_plane(sample, cKDTree(sample), tilted(true_normal), true_offset, None,
                                                    1e-9)
    assert abs(abs(normal @ true_normal) - 1) < 1e-10 and abs(abs(offset) - abs(true_offset)) < 1e-9 * cow.diagonal

    bent = evenly(synthetic.bend(cow.points, 1.0), mirror_planes.ICP_SAMPLES)
    start = tilted(np.array([1.0, 0.0, 0.0])), float(np.mean(bent[:, 0]))
    accelerated = mirror_planes._refine_plane(bent, cKDTree(bent), *start, None, 1e-4)[2]
    monkeypatch.setattr(mirror_planes, "ANDERSON_MEMORY", 1)  # plain ICP
    capped = mirror_planes._refine_plane(bent, cKDTree(bent), *start, None, 1e-4)[2]
    monkeypatch.setattr(mirror_planes, "ICP_ITERATIONS", 200)
    converged = mirror_planes._refine_plane(bent, cKDTree(bent), *start, None, 1e-6)[2]
    print("trimmed RMS: accelerated", accelerated, "plain 40 steps", capped, "plain 200 steps", converged)
    assert accelerated <= converged * 1.001 and accelerated <= capped * (1 + 1e-6)


def test_the_weights_at_several_widths_from_one_search_equal_each_searched_alone():
    """phi and theta from one neighbour search at the larger width: the same matrices, entry for entry, as the
    weights found at each width alone (and one matrix for a width given twice)."""
    rng = np.random.default_rng(4)
    p = rng.normal(size=(3000, 3))
    q = p * [-1, 1, 1] + 0.01 * rng.normal(size=(3000, 3))
    wide, narrow, again = pair_weights_at(p, q, [0.3, 0.2, 0.3])
    assert again is wide
    for width, matrix in ((0.3, wide), (0.2, narrow)):
        alone = pair_weights(p, q, width)
        assert matrix.nnz == alone.nnz > 3000 and abs(matrix - alone).max() == 0.0


@pytest.mark.parametrize("n", [3_000, 70_000])
def test_the_symmetric_weights_equal_scipys_conversion_with_few_and_with_more_than_65536_pairs(n):
    """The weight matrix built by the radix sort of its rows (one 16-bit pass up to 65,536 pairs, two beyond)
    equals scipy's own conversion of the same entries, entry for entry, each row's columns in any order."""
    rng = np.random.default_rng(5)
    i = rng.integers(0, n - 1, 5 * n)
    j = i + rng.integers(1, n - i)
    _, first = np.unique(np.column_stack([i, j]), axis=0, return_index=True)  # each pair once
    i, j, weight = i[first], j[first], rng.uniform(0.1, 1.0, len(first))
    built = _symmetric(n, i, j, weight)
    expected = sp.coo_matrix((np.concatenate([weight, weight, np.ones(n)]),
                              (np.concatenate([i, j, np.arange(n)]), np.concatenate([j, i, np.arange(n)]))),
                             shape=(n, n)).tocsr()
    assert built.nnz == expected.nnz == 2 * len(i) + n
    assert abs(built - expected).max() == 0.0
    assert np.array_equal(built.indptr, expected.indptr)


def test_farthest_point_sampling_on_many_points_is_the_plain_definition(monkeypatch):
    """On LOCAL_FROM points or more the later sweeps visit only what a k-d tree finds near the new sample; the
    samples are those of the definition: each the point farthest from all before it."""
    from scipy.spatial import cKDTree
    from filter_symblend.core import mesh_quantities
    trees = []
    monkeypatch.setattr(mesh_quantities, "cKDTree", lambda points: trees.append(points) or cKDTree(points))
    rng = np.random.default_rng(8)
    points = rng.normal(size=(mesh_quantities.LOCAL_FROM + 2000, 3)) * [3.0, 1.0, 0.2]
    chosen = mesh_quantities.farthest_point_order(points, 400, start=5)
    nearest = np.linalg.norm(points - points[5], axis=1)
    expected = [5]
    for _ in range(399):
        expected.append(int(np.argmax(nearest)))
        nearest = np.minimum(nearest, np.linalg.norm(points - points[expected[-1]], axis=1))
    np.testing.assert_array_equal(chosen, expected)
    assert len(trees) == 1, "the later sweeps must have gone through the tree"
