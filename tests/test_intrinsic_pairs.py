"""Automatic pairs beyond one mirror plane: the reflection registered onto the shape for bent and
compressed shapes, the intrinsic (Laplace-Beltrami) mirror map for articulated ones, whitening for compressed and sheared ones, and the choice between them."""

import warnings
from importlib import import_module

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from filter_symblend import GeometryError, SymblendWarning, symmetrize, synthetic
from filter_symblend.asymmetry import fit_mirror_plane
from filter_symblend.auto_pairs import WHITENED_DIRECTIONS, WHITENED_STARTS, intrinsic_correspondence
from filter_symblend.geometry import hemisphere_directions, whitening
from filter_symblend.mesh_geometry import mean_spacing
from filter_symblend.registration import registered_mirror_map
from filter_symblend.spectral import laplace_eigenfunctions
from filter_symblend.surface_symmetry import fit_surface_mirror_plane, promising_normals

from test_twin_completion import against_100_landmarks


def unit_sphere(count: int = 4000):
    """A triangulated unit sphere: the convex hull of a Fibonacci spiral of ``count`` points."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    angle = np.pi * (1.0 + np.sqrt(5.0)) * k
    points = np.column_stack([np.sqrt(1 - z**2) * np.cos(angle), np.sqrt(1 - z**2) * np.sin(angle), z])
    return points, ConvexHull(points).simplices


def test_sphere_eigenfunctions_are_the_spherical_harmonics():
    """On the unit sphere the Laplace-Beltrami eigenvalues are l(l + 1), 2l + 1 times each; the
    eigenfunctions of l = 1 are the coordinates. With the areas normalized to total 1 the
    eigenvalues scale by the area 4 pi."""
    points, faces = unit_sphere()
    functions, areas = laplace_eigenfunctions(points, faces, 9)
    assert areas.sum() == pytest.approx(1.0)
    np.testing.assert_allclose(functions.T @ (areas[:, None] * functions), np.eye(9), atol=1e-8)
    from filter_symblend.spectral import cotangent_laplacian
    stiffness, _ = cotangent_laplacian(points, faces)
    values = np.einsum("ni,ni->i", functions, stiffness @ functions) / (4 * np.pi)
    np.testing.assert_allclose(values, [0, 2, 2, 2, 6, 6, 6, 6, 6], atol=0.02 * 6)
    # the l = 1 eigenspace is spanned by x, y, z
    coefficients = np.linalg.lstsq(points, functions[:, 1:4], rcond=None)[0]
    np.testing.assert_allclose(points @ coefficients, functions[:, 1:4], atol=0.01)


def test_hemisphere_directions_are_unit_spread_and_on_one_side():
    directions = hemisphere_directions(200)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0)
    assert (directions[:, 2] >= 0).all()
    cosines = np.abs(directions @ directions.T)[~np.eye(200, dtype=bool)]
    assert cosines.max() < np.cos(np.radians(5))  # no two planes within 5 degrees
    # and every plane normal is within 8 degrees of one of them
    probe = np.random.default_rng(0).normal(size=(2000, 3))
    probe /= np.linalg.norm(probe, axis=1, keepdims=True)
    assert np.abs(probe @ directions.T).max(axis=1).min() > np.cos(np.radians(8))


@pytest.mark.parametrize("seed", [None, 7, 8])
def test_a_sheared_symmetric_shape_is_mirror_symmetric_once_whitened(cow, seed):
    sheared = synthetic.compress(cow.points, [1, 1, 0], 0.6, shear=0.2)
    if seed is not None:
        sheared = synthetic.random_rigid(sheared, seed)
    white = (sheared - sheared.mean(axis=0)) @ whitening(sheared)
    np.testing.assert_allclose(np.cov(white.T, bias=True), np.eye(3), atol=1e-12)
    starts = promising_normals(white, hemisphere_directions(WHITENED_DIRECTIONS), WHITENED_STARTS)
    plane = fit_surface_mirror_plane(white, axes=starts)
    mirrored = white[cow.all_left] - 2 * (white[cow.all_left] @ plane[0] - plane[1])[:, None] * plane[0]
    # a few vertices of the cow have no exact twin, so the covariance is symmetric to about 1e-4
    assert np.abs(mirrored - white[cow.all_right]).max() < 2e-3 * np.ptp(white, axis=0).max()


def test_the_intrinsic_map_pairs_a_strongly_bent_shape_where_one_plane_cannot(cow):
    bent = synthetic.random_rigid(synthetic.bend(cow.points, 1.2), seed=4)
    plane = fit_surface_mirror_plane(bent)
    correspondence = intrinsic_correspondence(bent, cow.faces, *plane)
    twin = np.full(len(cow.points), -1)
    twin[cow.all_left], twin[cow.all_right] = cow.all_right, cow.all_left
    paired = (correspondence.partner >= 0) & (twin >= 0) & (correspondence.partner != np.arange(len(twin)))
    error = np.linalg.norm(cow.points[correspondence.partner[paired]] - cow.points[twin[paired]], axis=1)
    error /= mean_spacing(cow.points, cow.faces)
    print(f"paired {correspondence.paired_fraction:.2f}, twin error (edges): median {np.median(error):.2f}, "
          f"90 % {np.quantile(error, 0.9):.2f}")
    assert correspondence.paired_fraction > 0.4  # measured 0.49 (one plane: 0.25)
    assert np.median(error) < 0.25 and np.quantile(error, 0.9) < 1.0  # measured 0.0 and 0.57
    # sides are consistent: every left vertex of the correspondence is on the cow's true left
    left = correspondence.side > 0
    assert np.mean(np.sign(cow.points[left, 0] - cow.offset) > 0) > 0.95


def _sym_errors(cow, deformed, mode="affine"):
    """Symmetry error over all vertex pairs of the input, of 100 landmark pairs and of pairs='auto',
    the shape error of the last two, and the auto result."""
    left, right = cow.landmarks(100)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SymblendWarning)
        landmarks = symmetrize(deformed, left, right, mode=mode)
    automatic = symmetrize(deformed, faces=cow.faces, pairs="auto", mode=mode)
    errors = [synthetic.symmetry_error(p, cow.all_left, cow.all_right) for p in
              (deformed, landmarks.points, automatic.points)]
    shapes = [synthetic.shape_error(p, cow.points) for p in (landmarks.points, automatic.points)]
    return errors, shapes, automatic


# Measured: 0.248 % against 0.367 % for 100 landmark pairs (the target's 5x is not met here: the joint's
# twins are predicted an edge or more off, and the completion gets some wrong; 0.365 % before it).
def test_an_articulated_shape_needs_no_landmarks(cow):
    """Without landmarks, the intrinsic pairs symmetrize a limb swung by 0.6 rad at least as well as 100
    hand-placed pairs."""
    weights = synthetic.limb_weights(cow.points, **synthetic.LIMBS["cow"])
    deformed = synthetic.random_rigid(synthetic.articulate_limb(cow.points, weights, 0.6), seed=7)
    errors, _, automatic = _sym_errors(cow, deformed)
    print("symmetry error, input / 100 landmarks / auto:", errors)
    assert automatic.report["auto_pairs"]["rounds"][0]["first_pairs"] == "intrinsic"
    assert errors[2] < errors[0] / 5  # measured 11x
    assert errors[2] < errors[1]  # measured 1.5x


# The target: at most 1/5 of the symmetry error of 100 landmark pairs, shape no worse. Measured
# (100 landmarks -> auto, % of the diagonal): bend 0.2 rad 0.036 -> 0.0003, bend 0.6 rad 0.107 -> 0.0009,
# bend 1.2 rad 0.207 -> 0.0167, bend 0.2 rad + compression 0.9 0.036 -> 0.0003, bend 0.4 rad +
# compression 0.85 0.071 -> 0.0009 (0.031 before the band around the midline was grown again, 0.0059
# with 1000 automatic pairs).
@pytest.mark.parametrize(("angle", "factor"), [(0.2, 1.0), (0.6, 1.0), (1.2, 1.0), (0.2, 0.9), (0.4, 0.85)])
def test_bent_and_compressed_shapes_need_no_landmarks(cow, angle, factor):
    """Registered onto its reflection, a bent (and compressed) cow is symmetrized five times better
    than with 100 hand-placed pairs, and its shape restored at least as well."""
    deformed = synthetic.bend(cow.points, angle)
    if factor != 1.0:
        deformed = synthetic.compress(deformed, [1, 1, 0], factor, shear=0.05)
    errors, shapes, automatic = _sym_errors(cow, synthetic.random_rigid(deformed, seed=7))
    print(f"bend {angle}, compression {factor}: symmetry error, input / 100 landmarks / auto:", errors,
          "shape error, 100 landmarks / auto:", shapes)
    assert automatic.report["auto_pairs"]["rounds"][0]["first_pairs"] == "registration"
    assert errors[2] < errors[1] / 5
    assert shapes[1] <= shapes[0]


def test_by_default_every_automatic_pair_found_on_a_small_mesh_enters_the_solve(cow):
    """The warp is exactly symmetric at the pairs and interpolates between them: capped at 1000 of the
    cow's pairs (the default before), the bent cow stays five times less symmetric."""
    bent = synthetic.random_rigid(synthetic.bend(cow.points, 0.4), seed=7)
    every = symmetrize(bent, faces=cow.faces, pairs="auto")
    capped = symmetrize(bent, faces=cow.faces, pairs="auto", auto_pair_count=1000)
    counts = [r.report["auto_pairs"]["pair_count"] + r.report["auto_pairs"]["midline_count"] for r in (every, capped)]
    errors = [synthetic.symmetry_error(r.points, cow.all_left, cow.all_right) for r in (every, capped)]
    print("pairs and midline points, symmetry error: every pair", counts[0], errors[0], "capped", counts[1], errors[1])
    assert counts[0] > 1400 and counts[1] == 1000  # measured 1475
    assert errors[0] < errors[1] / 5  # measured 0.0005 % against 0.0064 %


def test_registration_pairs_the_sampled_vertices_of_a_bent_cow_with_their_true_twins(cow):
    bent = synthetic.random_rigid(synthetic.bend(cow.points, 0.6), seed=4)
    sample, twin, round_trip = registered_mirror_map(bent, cow.faces, *fit_surface_mirror_plane(bent))
    partner = np.full(len(cow.points), -1)
    partner[cow.all_left], partner[cow.all_right] = cow.all_right, cow.all_left
    known = partner[sample] >= 0
    # of 2000, those whose reflection lands off every vertex or whose twin's twin is not themselves are
    # dropped (measured 1940), mostly the vertices near the cow's midline that have no exact twin
    assert len(sample) > 1900
    np.testing.assert_array_equal(round_trip, sample)
    assert np.mean(twin[known] == partner[sample][known]) > 0.99  # measured 1.0 (one plane: 0.1)


def test_without_the_normal_term_registration_undoes_the_reflection(cow, monkeypatch):
    """The smoothest field that moves the reflection of a strongly bent cow onto it is the one that
    undoes the reflection, every vertex its own twin; the normals rule it out."""
    from filter_symblend import registration
    bent = synthetic.random_rigid(synthetic.bend(cow.points, 1.2), seed=7)
    plane = fit_surface_mirror_plane(bent)
    partner = np.full(len(cow.points), -1)
    partner[cow.all_left], partner[cow.all_right] = cow.all_right, cow.all_left

    def apart(sample):  # the sampled vertices whose true twin is 3 edges away or more
        return (partner[sample] >= 0) & (np.linalg.norm(bent[sample] - bent[partner[sample]], axis=1)
                                         > 3 * mean_spacing(bent, cow.faces))

    sample, twin, _ = registered_mirror_map(bent, cow.faces, *plane)
    monkeypatch.setattr(registration, "NORMAL_WEIGHT", 0.0)
    blind_sample, blind_twin, _ = registered_mirror_map(bent, cow.faces, *plane)
    assert np.mean(twin[apart(sample)] == partner[sample][apart(sample)]) > 0.95  # measured 0.98
    # its own twin (measured 1.0)
    assert np.mean(blind_twin[apart(blind_sample)] == blind_sample[apart(blind_sample)]) > 0.9


def test_a_compressed_and_sheared_shape_is_restored_exactly_without_landmarks(cow):
    sheared = synthetic.random_rigid(synthetic.compress(cow.points, [1, 1, 0], 0.6, shear=0.2), seed=7)
    result = symmetrize(sheared, faces=cow.faces, pairs="auto", mode="affine")
    auto = result.report["auto_pairs"]
    assert auto["rounds"][0]["first_pairs"] == "whitened mirror plane"
    assert "intrinsic" not in auto["first_candidates"]  # the whitened plane paired 97 %: no need to try
    assert synthetic.symmetry_error(result.points, cow.all_left, cow.all_right) < 1e-4  # measured 1e-5


def test_rounds_that_do_not_make_the_surface_more_symmetric_are_not_kept(cow):
    bent = synthetic.random_rigid(synthetic.bend(cow.points, 1.2), seed=7)
    result = symmetrize(bent, faces=cow.faces, pairs="auto", mode="affine")
    rounds = result.report["auto_pairs"]["rounds"]
    kept = [entry["surface_asymmetry"] for entry in rounds if entry.get("kept", True) and "pairs" in entry]
    assert kept == sorted(kept, reverse=True)
    assert import_module("filter_symblend.symmetrize")._surface_asymmetry(result, cow.faces) == kept[-1]
    if result.report["auto_pairs"]["stopped"] == "no gain":
        assert rounds[-1]["kept"] is False and rounds[-1]["surface_asymmetry"] >= kept[-1]


def test_the_surface_plane_of_an_obliquely_compressed_bend_is_found_from_the_screened_starts(cow):
    """Under the Figure 1 map (bend 1.2 rad, then oblique compression and shear) the planes normal to the
    principal axes end far from the plane of the true pairs (measured 14-87 degrees); the default starts
    add the most promising of many directions, and the plane found is within 3 degrees of it (2.8)."""
    deformed = synthetic.random_rigid(synthetic.figure_1_deformation(cow.points), seed=7)
    truth = fit_mirror_plane(deformed[cow.all_left], deformed[cow.all_right]).normal
    centred = deformed - deformed.mean(axis=0)
    principal = np.linalg.svd(centred, full_matrices=False)[2]

    def degrees_off(normal):
        return np.degrees(np.arccos(min(1.0, abs(normal @ truth))))

    assert degrees_off(fit_surface_mirror_plane(deformed, axes=principal)[0]) > 10
    assert degrees_off(fit_surface_mirror_plane(deformed)[0]) < 3


def test_the_cow_under_the_figure_1_map_comes_back_exactly_symmetric_without_landmarks(cow):
    """The registration from the right plane pairs the cow under the Figure 1 map (it was refused when the
    plane came from the principal axes alone), its short pairs near the midline are kept, and only the
    twins that land on a vertex and whose round trip is exact (grown instead, 38 vertices near the
    midline took a neighbour of their twin: 0.070 %). Measured: symmetry error 1e-15 of the diagonal
    against 0.213 % with 100 landmarks; shape 1.357 % against 1.614 %."""
    deformed = synthetic.random_rigid(synthetic.figure_1_deformation(cow.points), seed=7)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SymblendWarning)
        errors, shapes, report = against_100_landmarks(cow, deformed, "affine")
    print("cow Figure 1: symmetry error 100 landmarks / auto", errors, "shape", shapes)
    assert report["auto_pairs"]["rounds"][0]["first_pairs"] == "registration"
    assert errors[1] < 1e-6 and errors[1] < errors[0] / 5
    assert shapes[1] <= shapes[0]


def test_a_shape_no_candidate_can_pair_is_refused_naming_each_candidate(cow, monkeypatch):
    """The Figure 1 map (bend, then oblique compression and shear) with the surface plane searched from the
    principal axes alone (a wrong plane, 70 degrees off) defeats every candidate: three pair too few
    vertices, and the registration's pairs fall apart into groups; so it is refused, each candidate
    named with its reason."""
    monkeypatch.setattr(import_module("filter_symblend.surface_symmetry"), "SCREENED_STARTS", 0)
    deformed = synthetic.random_rigid(synthetic.figure_1_deformation(cow.points), seed=7)
    with pytest.raises(GeometryError, match=r"no usable mirror pairs \(mirror plane: rejected: it pairs \d+% of the "
                       r"vertices, fewer than 20%; whitened mirror plane: rejected: .*; registration: .*; "
                       r"intrinsic: rejected: .*\)\. "
                       r"The shape may be too far .* use pairs='landmarks\+auto'\."):
        symmetrize(deformed, faces=cow.faces, pairs="auto", mode="affine")


def test_a_point_cloud_skips_the_registration_and_intrinsic_candidates_and_says_why(cow):
    bent = synthetic.bend(cow.points, 0.2)
    result = symmetrize(bent, pairs="auto", mode="affine")
    candidates = result.report["auto_pairs"]["first_candidates"]
    assert candidates["registration"] == ("the registration candidate needs triangles (oriented normals); "
                                          "this is a point cloud")
    assert candidates["intrinsic"] == "the intrinsic candidate needs triangles; this is a point cloud"


def test_a_mesh_above_the_size_limit_skips_the_intrinsic_candidate_and_says_why(cow, monkeypatch):
    from filter_symblend import auto_pairs
    monkeypatch.setattr(auto_pairs, "INTRINSIC_VERTEX_LIMIT", 1000)
    monkeypatch.setattr(import_module("filter_symblend.symmetrize"), "GLOBALLY_SYMMETRIC", 1.1)  # try every source
    result = symmetrize(synthetic.bend(cow.points, 0.2), faces=cow.faces, pairs="auto")
    assert result.report["auto_pairs"]["first_candidates"]["intrinsic"] == (
        "skipped: the mesh has 2,904 vertices, the intrinsic candidate is tried up to 1,000")


def test_a_failed_eigenproblem_drops_the_intrinsic_candidate_with_its_reason(cow, monkeypatch):
    from scipy.sparse.linalg import ArpackNoConvergence

    from filter_symblend import spectral

    def no_convergence(*args, **kwargs):
        raise ArpackNoConvergence("No convergence", np.zeros(0), np.zeros((0, 0)))

    monkeypatch.setattr(spectral, "eigsh", no_convergence)
    monkeypatch.setattr(import_module("filter_symblend.symmetrize"), "GLOBALLY_SYMMETRIC", 1.1)  # try every source
    result = symmetrize(synthetic.bend(cow.points, 0.2), faces=cow.faces, pairs="auto")
    assert result.report["auto_pairs"]["first_candidates"]["intrinsic"] == (
        "the Laplace-Beltrami eigenproblem failed (ARPACK error -1: No convergence)")


def test_a_later_round_that_finds_too_few_pairs_keeps_the_last_good_result(cow, monkeypatch):
    from filter_symblend.auto_pairs import MirrorCorrespondence
    module = import_module("filter_symblend.symmetrize")
    bent = synthetic.bend(cow.points, 0.2)
    first = symmetrize(bent, faces=cow.faces, pairs="auto", auto_iterations=1)
    monkeypatch.setattr(module, "mirror_correspondence", lambda points, *args, **kwargs: MirrorCorrespondence(
        np.full(len(points), -1), np.zeros(len(points), dtype=np.int8), 0, 0))
    result = symmetrize(bent, faces=cow.faces, pairs="auto")
    auto = result.report["auto_pairs"]
    assert auto["stopped"] == "round failed" and not auto["converged"]
    assert auto["rounds"][-1]["kept"] is False
    assert auto["rounds"][-1]["failed"].startswith("Automatic pairing found 0 mirror pair(s) on the surface")
    np.testing.assert_array_equal(result.points, first.points)


def test_a_mesh_too_small_for_the_eigenbasis_is_refused_by_the_intrinsic_map():
    from filter_symblend.spectral import intrinsic_mirror_map
    points, faces = unit_sphere(200)
    with pytest.raises(GeometryError, match=r"^the mesh has 200 vertices, the intrinsic map needs 240$"):
        intrinsic_mirror_map(points, faces, np.arange(200))
