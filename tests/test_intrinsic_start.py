"""The intrinsic start (issue 46): when no map mirrors enough of a posed body, the intrinsic mirror's own
vertex pairs are solved; a shape with no mirror symmetry is still refused, and says why."""

import warnings

import numpy as np
import pymeshlab
import pytest
from scipy.spatial import cKDTree

from filter_symblend import SymblendWarning, SymmetryNotFoundError
from filter_symblend.auto.config import DEFAULT
from filter_symblend.testing import synthetic
from filter_symblend.auto.intrinsic_start import cannot_start, intrinsic_start
from filter_symblend.auto.rounds import plane_distances, surface_asymmetry
from filter_symblend.auto.spectral import DESCRIPTOR_AGREEMENT, descriptor_disagreement
from filter_symblend.auto.surface import build_surface
from filter_symblend.core.landmark_pairs import check_landmarks
from filter_symblend.core.mirror_planes import surface_mirror_planes
from filter_symblend.core.solve import solve
from conftest import SAMPLE_MESHES, symmetric_blob, twins

pytestmark = pytest.mark.auto


def _start(points, faces):
    surface = build_surface(points, faces)
    sample = surface.usable_index

    def solve_pairs(left, right):
        ones = np.ones(len(left))
        checked = check_landmarks(points, left, right, np.arange(1, len(left) + 1), None, ones, ones)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SymblendWarning)
            return solve(points, checked, {"mode": "articulated", "phi_width": 8.0, "theta_width": 5.0,
                                           "width_spacing": 0.0, "alpha": 0.01, "output_frame": "input"}, warn=False)

    distances = plane_distances(surface, *surface_mirror_planes(points[sample])[0], sample)
    before = float(np.sqrt(np.mean(distances**2)))  # RMS, as surface_asymmetry measures an output
    result, tried = intrinsic_start(surface, DEFAULT, solve_pairs, lambda out: surface_asymmetry(surface, out, sample))
    return result, tried, before


def test_the_descriptor_disagreement_of_the_true_mirror_is_nil_and_of_a_random_map_about_one():
    points, faces = symmetric_blob(3)
    from filter_symblend.auto.spectral import eigenbasis, heat_kernel_signatures
    signatures = heat_kernel_signatures(eigenbasis(points, faces, 30), 8)
    assert descriptor_disagreement(signatures, twins(points)) < 1e-3
    random_map = np.random.default_rng(1).permutation(len(points))
    assert 0.7 < descriptor_disagreement(signatures, random_map) < 1.3


def test_the_eigenbasis_is_the_same_on_every_call_even_where_eigenvalues_repeat():
    """A sphere's eigenvalues repeat (2l + 1 times): with ARPACK's random start each call spans each eigenspace
    by other functions (measured: 0.3 apart), and every map built on them would differ from run to run."""
    from filter_symblend.auto.spectral import eigenbasis
    points, faces = synthetic.icosphere(3)
    first, second = eigenbasis(points, faces, 20), eigenbasis(points, faces, 20)
    assert np.isclose(first.values[1], first.values[3], rtol=1e-2)  # the three functions of degree 1
    assert np.array_equal(first.functions, second.functions) and np.array_equal(first.values, second.values)


def _textbook_functional_map(basis, count, descriptors, operators):
    """The sign solve as Ren et al. write it: scipy's least squares on the explicit (count^2 (d + 2), count^2)
    design matrix of vec(C) (the descriptors kept, each orientation operator anticommuted, the Laplacian
    commuted), projected onto the involutions."""
    from filter_symblend.auto.spectral import COMMUTATIVITY_WEIGHT, closest_symmetric_orthogonal
    functions = basis.functions[:, :count]
    coefficients = functions.T @ (basis.mass[:, None] * descriptors)
    identity, scale = np.eye(count), np.linalg.norm(coefficients)
    rows, right = [np.kron(coefficients.T, identity)], [coefficients.reshape(-1, order="F")]
    for operator in operators[:, :count, :count]:
        operator = operator * (scale / np.linalg.norm(operator))
        rows.append(np.kron(operator.T, identity) + np.kron(identity, operator))
        right.append(np.zeros(count * count))
    values = basis.values[:count] / basis.values[count - 1]
    gaps = ((values[:, None] - values[None, :]) ** 2).reshape(-1, order="F")
    rows.append(COMMUTATIVITY_WEIGHT * scale * np.diag(gaps))
    right.append(np.zeros(count * count))
    solution = np.linalg.lstsq(np.vstack(rows), np.concatenate(right), rcond=None)[0]
    return closest_symmetric_orthogonal(solution.reshape(count, count, order="F"))


def test_the_sign_solve_by_its_normal_matrix_is_the_least_squares_on_the_design_matrix_and_finds_the_mirror():
    """The bumpy blob: at every first size, the functional map from the Kronecker identities' normal matrix is
    the explicit design matrix's least-squares map, an involution, and its point map the blob's exact mirror."""
    from filter_symblend.auto.spectral import (DESCRIPTOR_SCALES, STARTS, eigenbasis, heat_kernel_signatures,
                                               mirror_functional_map, orientation_operators, point_map)
    points, faces = symmetric_blob(3)
    basis = eigenbasis(points, faces, 30)
    descriptors = heat_kernel_signatures(basis, DESCRIPTOR_SCALES)
    operators = orientation_operators(points, faces, basis.functions[:, :max(STARTS)], descriptors)
    for count in STARTS:
        ours = mirror_functional_map(basis, count, descriptors, operators)
        np.testing.assert_allclose(ours, _textbook_functional_map(basis, count, descriptors, operators), atol=1e-9)
        np.testing.assert_allclose(ours @ ours, np.eye(count), atol=1e-9)
        np.testing.assert_array_equal(point_map(basis.functions[:, :count], ours), twins(points))


def _textbook_zoomout(basis, vertex_map, start, stop, step):
    """ZoomOut as Melzi et al. write it, every vertex at every step, nearest neighbours by a k-d tree."""
    from filter_symblend.auto.spectral import closest_symmetric_orthogonal
    for count in range(start, stop + 1, step):
        functions = basis.functions[:, :count]
        functional = closest_symmetric_orthogonal(functions.T @ (basis.mass[:, None] * functions[vertex_map]))
        vertex_map = cKDTree(functions).query(functions @ functional)[1]
    return vertex_map


def test_zoomout_on_a_sample_recovers_the_exact_mirror_and_on_every_vertex_is_the_textbook_zoomout():
    """The bumpy blob (2,562 vertices), its exact mirror map spoiled at a third of the vertices: ZoomOut's steps on
    a 500-vertex sample (each with the mass of the vertices nearest it) give back every vertex's exact twin; with
    every vertex as the sample, the steps are the textbook ZoomOut's."""
    from filter_symblend.auto.spectral import SpectralSample, eigenbasis, zoomout
    points, faces = symmetric_blob(4)
    basis = eigenbasis(points, faces, 40)
    rng = np.random.default_rng(2)
    true = twins(points)
    spoiled = np.where(rng.random(len(points)) < 1 / 3, rng.integers(0, len(points), len(points)), true)
    sample = SpectralSample.of(points, basis.mass, 500)
    assert len(sample.vertices) == 500 and sample.mass.sum() == pytest.approx(basis.mass.sum(), rel=1e-12)
    np.testing.assert_array_equal(zoomout(basis, spoiled[sample.vertices], 10, 40, 5, sample), true)
    every = SpectralSample.of(points, basis.mass, len(points))
    ours = zoomout(basis, spoiled, 10, 40, 5, every)
    assert np.mean(ours == _textbook_zoomout(basis, spoiled, 10, 40, 5)) > 0.999  # float32 distances: near ties


def test_the_reversed_share_is_one_for_the_mirror_and_nil_for_the_identity_a_rotation_and_a_collapse():
    """An icosphere is closed under x -> -x (a mirror) and (x, y) -> (-x, -y) (a half turn)."""
    from filter_symblend.auto.spectral import reversed_share, reversed_triangles
    points, faces = synthetic.icosphere(3)
    tree = cKDTree(points)
    mirror, half_turn = (tree.query(points * sign)[1] for sign in ([-1.0, 1.0, 1.0], [-1.0, -1.0, 1.0]))
    assert np.all(np.linalg.norm(points[half_turn] - points * [-1.0, -1.0, 1.0], axis=1) < 1e-9)
    shares = {name: reversed_share(points, faces, reversed_triangles(points, faces, vertex_map))
              for name, vertex_map in [("mirror", mirror), ("identity", np.arange(len(points))),
                                       ("half turn", half_turn), ("collapse", np.zeros(len(points), dtype=int))]}
    assert shares == {"mirror": 1.0, "identity": 0.0, "half turn": 0.0, "collapse": 0.0}
    folded = mirror.copy()  # the mirror everywhere but on one side of y = 0, where it is the identity
    folded[points[:, 1] > 0] = np.flatnonzero(points[:, 1] > 0)
    assert 0.3 < reversed_share(points, faces, reversed_triangles(points, faces, folded)) < 0.7


def test_a_map_that_folds_two_caps_onto_themselves_tears_and_its_refit_on_the_continuous_part_is_the_mirror():
    """The bumpy blob's exact mirror, but two twin caps (a quarter of the surface, away from the midline) each mapped
    onto itself by its own reflection, as ZoomOut maps a posed body's arms: every triangle is still reversed, but
    the map tears along the caps' rims, so the mirrored share counts the rest only; the functional map refitted
    on the continuous part gives back every exact twin."""
    from filter_symblend.auto.spectral import (SpectralSample, continuous_part, eigenbasis, mirrored_share, refit,
                                               reversed_share, reversed_triangles, zoomout)
    points, faces = symmetric_blob(4)
    true = twins(points)
    centre = points[np.argmax(points[:, 0])] * [1.0, 1.0, 1.0]
    folded = true.copy()
    tree = cKDTree(points)
    for side in (1.0, -1.0):
        middle = centre * [side, 1.0, 1.0]
        cap = np.flatnonzero(np.linalg.norm(points - middle, axis=1) < 0.6)
        folded[cap] = tree.query(points[cap] * [1.0, -1.0, 1.0] + [0.0, 2.0 * middle[1], 0.0])[1]
    basis = eigenbasis(points, faces, 40)
    area_share = lambda where: reversed_share(points, faces, where)  # noqa: E731
    caps = folded != true
    print("caps' share of the vertices", caps.mean())
    assert 0.1 < caps.mean() < 0.35
    assert area_share(reversed_triangles(points, faces, folded)) > 0.97  # the caps' triangles are reversed too
    part = continuous_part(points, faces, folded, basis.mass)
    assert not part[caps].any() and part[~caps].mean() > 0.95
    shares = [mirrored_share(points, faces, vertex_map, basis.mass) for vertex_map in (true, folded)]
    beside_caps = area_share(~caps[faces].any(axis=1))
    assert shares[0] == 1.0 and beside_caps - 0.05 < shares[1] <= beside_caps + 1e-12
    sample = SpectralSample.of(points, basis.mass, 800)
    assert np.mean(zoomout(basis, folded[sample.vertices], 12, 40, 4, sample) == true) < 0.9  # ZoomOut keeps the fold
    refitted = refit(basis, folded, part, 12, 4, sample)
    assert np.mean(refitted == true) > 0.99
    assert mirrored_share(points, faces, refitted, basis.mass) > 0.99


def test_a_swung_limb_is_paired_by_the_intrinsic_mirror(cow):
    """The exactly symmetric cow, a front leg swung 1 rad at its joint (an isometry but for the joint): the
    start's output is five times more symmetric than the input over the ground truth's own twins."""
    weights = synthetic.limb_weights(cow.points, **synthetic.LIMBS["cow"])
    posed = synthetic.articulate_limb(cow.points, weights, 1.0)
    result, tried, before = _start(posed, cow.faces)
    assert result is not None and tried["chosen"] in tried["starts"]
    chosen = tried["starts"][tried["chosen"]]
    assert chosen["descriptor_disagreement"] < DESCRIPTOR_AGREEMENT and chosen["pairs"] > 100
    errors = [synthetic.symmetry_error(p, cow.all_left, cow.all_right) for p in (posed, result.points)]
    print("symmetry error over the true twins, input / the start's output:", errors)
    assert errors[1] < 0.3 * errors[0]
    assert chosen["surface_asymmetry"] < before


def test_a_shape_without_mirror_symmetry_gives_no_start_and_says_why():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(SAMPLE_MESHES / "bunny.obj"))
    ms.meshing_decimation_quadric_edge_collapse(targetfacenum=10000)
    points, faces = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    result, tried, before = _start(points, faces)
    assert result is None
    assert min(entry["descriptor_disagreement"] for entry in tried["starts"].values()) > DESCRIPTOR_AGREEMENT
    assert cannot_start(tried).startswith(
        "Its intrinsic mirror does not keep the shape's heat kernel signatures (disagreement 0.")
    assert cannot_start({"starts": {}}) == (
        "The shape's intrinsic mirror could not be computed (a point cloud, or no spectrum).")
    unsolved = {"starts": {8: {"descriptor_disagreement": 0.01, "pairs": 300, "refused": "pairs fall apart"}}}
    assert cannot_start(unsolved) == "Its intrinsic mirror's pairs could not be solved (pairs fall apart)."
    too_few = {"starts": {8: {"descriptor_disagreement": 0.01, "pairs": 2}}}
    assert cannot_start(too_few) == "Its intrinsic mirror's pairs could not be solved (too few pairs apart)."


def test_a_run_started_by_the_intrinsic_mirror_says_so_and_other_modes_refuse(cow):
    """With every map made to fall short (min_coverage 99 %), the articulated run of the posed cow starts from its
    intrinsic mirror, comes back about five times more symmetric over the true twins, and warns that it rests on that
    mirror; the standard mode refuses and names the articulated mode."""
    from filter_symblend import symmetrize
    from filter_symblend.auto import AutoConfig
    from filter_symblend.auto.rounds import INTRINSIC_START_WARNING
    weights = synthetic.limb_weights(cow.points, **synthetic.LIMBS["cow"])
    posed = synthetic.random_rigid(synthetic.articulate_limb(cow.points, weights, 1.0), seed=3)
    strict = AutoConfig(min_coverage=0.99, precise_coverage=0.99)
    with pytest.warns(SymblendWarning) as caught:
        result = symmetrize(posed, faces=cow.faces, pairs="auto", mode="articulated", auto_config=strict)
    assert INTRINSIC_START_WARNING in [str(w.message) for w in caught]
    report = result.report.auto_pairs
    assert report.intrinsic_start["chosen"] in report.intrinsic_start["starts"]
    assert report.rounds[0].start == "intrinsic" and INTRINSIC_START_WARNING in report.warnings
    assert INTRINSIC_START_WARNING in result.report.warnings
    errors = [synthetic.symmetry_error(p, cow.all_left, cow.all_right) for p in (posed, result.points)]
    assert errors[1] < 0.3 * errors[0]  # measured 0.2
    assert result.mirror_pairs is not None and result.mirror_pairs.report.coverage > 0.5
    with pytest.raises(SymmetryNotFoundError, match=r"If it is a posed body, mode='articulated' pairs it by its "
                                                     r"intrinsic mirror\. Place landmark pairs"):
        symmetrize(posed, faces=cow.faces, pairs="auto", mode="standard", auto_config=strict)
