"""Automatic pairs against ground truth that does not mirror its tessellation: an exactly symmetric mesh
remeshed so that no vertex has an exact twin (its twins are points of the surface), deformed by known maps;
a limb swung at a joint; a body of revolution whose parts decide its mirror (several pieces strongly bent:
tests/test_auto_pairs.py)."""

import warnings

import numpy as np
import pytest

from filter_symblend import SymblendWarning, symmetrize
from filter_symblend.auto import AutoConfig
from filter_symblend.auto.spectral import candidate_mirrors, cotangent_laplacian, mended_map, working_mesh
from filter_symblend.testing import synthetic

from conftest import SHARED_DATA, remeshed_ground_truth, symmetric_blob, twins

pytestmark = pytest.mark.auto


def _landmarks_alone(deformed, left, right, mode):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SymblendWarning)
        return symmetrize(deformed, left, right, mode=mode)


DEFORMATIONS = {
    "bend 0.6 rad": lambda p: synthetic.bend(p, 0.6),
    "bend 0.4 rad + compression": lambda p: synthetic.compress(synthetic.bend(p, 0.4), [1, 1, 0], 0.85, shear=0.05),
}


@pytest.mark.parametrize("deformation", list(DEFORMATIONS))
def test_a_remeshed_deformed_cow_comes_back_more_symmetric_than_100_landmarks_make_it(remeshed_cow, deformation):
    """No vertex of the remeshed cow has an exact twin: the pairs are vertices and points of the surface.
    The issue's target is a fifth of the landmarks' error; what is asserted is what the layer reaches on
    every such case measured (docs/benchmarks.md has the table)."""
    truth = remeshed_cow
    deformed = synthetic.random_rigid(DEFORMATIONS[deformation](truth.points), seed=7)
    automatic = symmetrize(deformed, faces=truth.faces, pairs="auto", mode="affine")
    alone = _landmarks_alone(deformed, *truth.landmarks(100), "affine")
    errors = [truth.symmetry_error(p) for p in (deformed, automatic.points, alone.points)]
    print(deformation, "symmetry error input / auto / 100 landmarks:", errors)
    report = automatic.report.auto_pairs
    assert report.twins_are == "points of the surface"
    assert errors[1] < errors[2] and errors[1] < 0.1 * errors[0]
    assert 0.5 < report.consistency <= 1.0
    # The reported twins (each vertex's, with its confidence): the registered field's confident twins stand against
    # the intrinsic mirror's coarser opinion (which, allowed over them, put 4 % of the bent cow's twins 1 % off).
    off, confidence = _reported_twins_off(automatic, truth, deformed)
    print("reported twins within 1 % of the diagonal:", np.mean(off < 0.01))
    assert np.mean(off < 0.01) > 0.97
    assert np.mean((confidence >= 0.5) & (off > 0.02)) < 0.005


def test_the_whitened_shapes_intrinsic_mirror_survives_a_compression_that_breaks_the_shapes_own(remeshed_cow):
    """Compressed to 65 % along an oblique direction with a shear, the remeshed cow's surface distances are no
    longer mirror-symmetric: the intrinsic mirror's pairs miss their true twins by a median 2 % of the diagonal.
    Whitened, the shape's symmetry is an isometry again, and its intrinsic mirror's pairs land on the true twins."""
    from scipy.spatial import cKDTree
    from filter_symblend.auto.intrinsic_map import intrinsic_pairs
    from filter_symblend.auto.surface import build_surface
    truth = remeshed_cow
    deformed = synthetic.random_rigid(synthetic.compress(truth.points, [1, 1, 0], 0.65, shear=0.15), seed=7)
    surface = build_surface(deformed, truth.faces)
    diagonal = np.linalg.norm(np.ptp(deformed, axis=0))
    row_of = np.full(len(deformed), -1)
    row_of[truth.left] = np.arange(len(truth.left))
    errors = {}
    for whitened in (False, True):
        x, y = intrinsic_pairs(surface, AutoConfig(), whitened)
        distance, vertex = cKDTree(deformed).query(x)
        known = (distance < 1e-9 * diagonal) & (row_of[vertex] >= 0)  # the pairs' sources are vertices
        assert np.count_nonzero(known) > 300
        errors[whitened] = np.linalg.norm(y[known] - truth.twins(deformed)[row_of[vertex[known]]], axis=1) / diagonal
    print("median twin error / diagonal, as is and whitened:", np.median(errors[False]), np.median(errors[True]))
    assert np.median(errors[False]) > 0.01
    assert np.median(errors[True]) < 0.005 and np.mean(errors[True] < 0.02) > 0.95


@pytest.mark.parametrize("mesh", ["cow", "spot"])
def test_a_field_let_slide_keeps_the_true_twins_at_the_rounded_ends_of_a_bend(remeshed_cow, mesh):
    """The remeshed mesh bent 1.2 rad; a field of the finest width fitted to its true twins, then registered let
    slide (the chosen field's registration). At the rounded ends of the bend any turn of the mirror lands on the
    surface; a ridge on the weights pulled the map back toward the plane reflection each step (the last tenth of the
    length: cow 94 %, spot 75 % of the twins left within 1 % of the diagonal); on the step, it keeps them."""
    from filter_symblend.auto.config import DEFAULT
    from filter_symblend.auto.field import RIDGE, MirrorField, field_centres, fit_to_pairs, register
    from filter_symblend.auto.first_map import _strided
    from filter_symblend.auto.surface import build_surface
    from filter_symblend.core.landmark_asymmetry import fit_mirror_plane
    if mesh == "spot" and not (SHARED_DATA / "spot.obj").exists():
        pytest.skip("../shared/data/spot.obj is absent")
    truth = remeshed_cow if mesh == "cow" else remeshed_ground_truth(SHARED_DATA / "spot.obj", 2.0)
    deformed = synthetic.random_rigid(synthetic.bend(truth.points, 1.2), seed=7)
    surface = build_surface(deformed, truth.faces)
    sample = _strided(surface, DEFAULT.registration_samples)
    x, y = deformed[truth.left], truth.twins(deformed)
    plane = fit_mirror_plane(x, y)
    field = MirrorField(plane.normal, plane.offset, field_centres(surface, sample, DEFAULT.field_centres),
                        DEFAULT.field_widths[-1] * surface.diagonal)
    fit_to_pairs(field, np.vstack([x, y]), np.vstack([y, x]), np.ones(2 * len(x)), RIDGE)
    along = truth.points[truth.left, 2]
    end = along > np.quantile(along, 0.9)
    assert np.all(np.linalg.norm(field(x) - y, axis=1)[end] < 0.01 * surface.diagonal)
    register(field, surface, sample, DEFAULT.field_iterations, DEFAULT, sliding=True)
    off = np.linalg.norm(field(x) - y, axis=1) / surface.diagonal
    print(mesh, "twins within 1 %, all and the last tenth:", np.mean(off < 0.01), np.mean(off[end] < 0.01))
    assert np.mean(off[end] < 0.01) > 0.97 and np.mean(off < 0.01) > 0.99


def test_an_intrinsic_mirror_chosen_on_a_posed_body_is_sharpened_by_a_field_where_the_field_holds(remeshed_cow):
    """The remeshed cow with a hind leg swung 0.3 rad, paired as a posed body: the intrinsic mirror is chosen (it
    follows the leg, no smooth field does) and its twins are coarse; the registered field's are precise on the body
    and wrong on the leg. The map chosen takes the field's twins where they land precisely and agree, the intrinsic
    mirror's elsewhere: the body's median twin error falls from 0.32 % of the diagonal to 0.11 % (measured), the
    leg's stays about the intrinsic mirror's (0.72 -> 0.75 %; the field's own there: 5.7 %, 0.6 rad)."""
    from scipy.spatial import cKDTree
    from filter_symblend.auto.config import DEFAULT
    from filter_symblend.auto.first_map import first_map
    from filter_symblend.auto.pairs import spread
    from filter_symblend.auto.surface import build_surface
    truth = remeshed_cow
    weights = synthetic.limb_weights(truth.points, **synthetic.LIMBS["cow"])
    deformed = synthetic.random_rigid(synthetic.articulate_limb(truth.points, weights, 0.3), seed=7)
    surface = build_surface(deformed, truth.faces)
    found = first_map(surface, spread(deformed, surface.usable_index, DEFAULT.score_samples), DEFAULT,
                      compression=False)
    assert found.map.name.startswith(f"{found.intrinsic.name} sharpened by the registration from the ")
    twin_weights = weights[cKDTree(truth.points).query(truth.twins(truth.points))[1]]
    on_leg = np.maximum(weights[truth.left], twin_weights) > 0
    x, y = deformed[truth.left], truth.twins(deformed)
    errors = {name: np.linalg.norm(mirror.predict(x) - y, axis=1) / surface.diagonal
              for name, mirror in (("chosen", found.map), ("intrinsic", found.intrinsic))}
    print({name: (np.median(error[~on_leg]), np.median(error[on_leg])) for name, error in errors.items()})
    assert np.median(errors["chosen"][~on_leg]) < 0.5 * np.median(errors["intrinsic"][~on_leg])
    assert np.median(errors["chosen"][on_leg]) < 1.25 * np.median(errors["intrinsic"][on_leg])  # the field's: 5.7 %


@pytest.mark.skipif(not (SHARED_DATA / "spot.obj").exists(), reason="../shared/data/spot.obj is absent")
def test_the_paper_figure_1_map_on_remeshed_spot_is_paired_by_the_whitened_shapes_intrinsic_mirror():
    """Spot remeshed, bent 1.2 rad and compressed to 65 % obliquely (the paper's Figure 1 map): every map of space
    slides a third of the twins by 4-12 % of the diagonal, and so did the intrinsic mirror, until the whitened
    shape's was a candidate (9.4x the symmetry error 100 landmarks leave, then 2.6x, 1.1x since the winning field is
    let slide along the surface toward its twins, 0.69x since its ridge damps the steps: docs/benchmarks.md)."""
    truth = remeshed_ground_truth(SHARED_DATA / "spot.obj", 2.0)
    deformed = synthetic.random_rigid(synthetic.figure_1_deformation(truth.points), seed=7)
    automatic = symmetrize(deformed, faces=truth.faces, pairs="auto", mode="affine")
    alone = _landmarks_alone(deformed, *truth.landmarks(100), "affine")
    errors = [truth.symmetry_error(p) for p in (deformed, automatic.points, alone.points)]
    print("Figure 1, symmetry error input / auto / 100 landmarks:", errors)
    assert automatic.report.auto_pairs.coverage["registration from the intrinsic mirror of the whitened shape"] \
        == max(share for name, share in automatic.report.auto_pairs.coverage.items() if not name.endswith("%"))
    assert errors[1] < 0.9 * errors[2]


def _reported_twins_off(result, truth, points) -> tuple[np.ndarray, np.ndarray]:
    """(distance of each true left vertex's reported twin from its true twin / diagonal, its confidence)."""
    twin, confidence = result.mirror_pairs.per_vertex()
    off = np.linalg.norm(twin[truth.left] - truth.twins(points), axis=1) / np.linalg.norm(np.ptp(points, axis=0))
    return off, confidence[truth.left]


def test_the_paper_figure_1_map_on_the_remeshed_cow_is_paired_once_the_fields_slide_is_spent(remeshed_cow):
    """The remeshed cow under Figure 1's map: the winning field lands on the surface in a few steps of its
    registration and then slides along it toward the true twins, as far as the involution term, which holds the
    images where they are, lets it. Held as firmly as while candidates are compared, it left a fifth of the twins
    more than 1 % of the diagonal off, 4 % of them confident (silent), and the output 1.7x as asymmetric as 100
    landmarks leave it; let slide (``field.SLIDING_INVOLUTION_WEIGHT``) it pairs 97 % (docs/benchmarks.md)."""
    truth = remeshed_cow
    deformed = synthetic.random_rigid(synthetic.figure_1_deformation(truth.points), seed=7)
    automatic = symmetrize(deformed, faces=truth.faces, pairs="auto", mode="affine")
    alone = _landmarks_alone(deformed, *truth.landmarks(100), "affine")
    off, confidence = _reported_twins_off(automatic, truth, deformed)
    errors = [truth.symmetry_error(p) for p in (automatic.points, alone.points)]
    print("twins within 1 %:", np.mean(off < 0.01), "symmetry error auto / 100 landmarks:", errors)
    assert np.mean(off < 0.01) > 0.95
    assert np.mean((confidence >= 0.5) & (off > 0.02)) < 0.01
    assert errors[0] < errors[1]


def test_a_remeshed_cow_bent_strongly_comes_back_more_symmetric_than_100_landmarks_make_it(remeshed_cow):
    """Bent 1.2 rad the remeshed cow is paired and made more symmetric than 100 landmarks make it: 0.46x their
    symmetry error since the chosen field's ridge damps its steps (0.79x before, its rounded ends left turned back
    toward the plane), not the fifth the issue asks (docs/benchmarks.md)."""
    truth = remeshed_cow
    deformed = synthetic.random_rigid(synthetic.bend(truth.points, 1.2), seed=7)
    automatic = symmetrize(deformed, faces=truth.faces, pairs="auto", mode="affine")
    alone = _landmarks_alone(deformed, *truth.landmarks(100), "affine")
    before, after, landmarks = (truth.symmetry_error(p) for p in (deformed, automatic.points, alone.points))
    print("bend 1.2 rad, symmetry error before / after / 100 landmarks:", before, after, landmarks)
    assert after < 0.6 * landmarks


def test_a_swung_limb_left_asymmetric_by_a_map_of_space_is_restored_from_the_intrinsic_start(remeshed_cow):
    """The remeshed cow with a hind leg swung 0.9 rad: the rounds from a map of space leave the leg unrestored
    (99th percentile of the output's distance to its reflection above 2 % of the diagonal), so the articulated
    mode runs them again from the intrinsic start and keeps that output, the more mirror-symmetric; against
    ground truth its error falls to about half (measured 2.00 -> 0.96 % of the diagonal, 100 landmark pairs
    0.66 %), and a warning says that it rests on the intrinsic mirror. (Swung 0.6 rad, the map of space now
    follows the leg: 0.62 %, 100 landmark pairs 0.56 %.)"""
    truth = remeshed_cow
    weights = synthetic.limb_weights(truth.points, **synthetic.LIMBS["cow"])
    deformed = synthetic.random_rigid(synthetic.articulate_limb(truth.points, weights, 0.9), seed=7)
    maps_only = symmetrize(deformed, faces=truth.faces, pairs="auto", mode="articulated",
                           auto_config=AutoConfig(part_left_asymmetric=1.0))
    assert maps_only.report.auto_pairs.output_asymmetry_p99 > AutoConfig().part_left_asymmetric
    with pytest.warns(SymblendWarning, match=r"the rounds from a map of space left a part of the output asymmetric "
                                             r"\(99th percentile [0-9.]+% of the diagonal\); the intrinsic mirror's "
                                             r"pairs \(a posed body\) restored it better"):
        automatic = symmetrize(deformed, faces=truth.faces, pairs="auto", mode="articulated")
    tried = automatic.report.auto_pairs.intrinsic_start
    assert tried["kept"] == "intrinsic" and tried["intrinsic_asymmetry"] < tried["maps_asymmetry"]
    assert tried["maps_asymmetry"] == pytest.approx(maps_only.report.auto_pairs.output_asymmetry)
    alone = _landmarks_alone(deformed, *truth.landmarks(100), "articulated")
    errors = [truth.symmetry_error(p) for p in (maps_only.points, automatic.points, alone.points)]
    print("limb swung 0.9 rad, symmetry error maps only / kept / 100 landmarks:", errors)
    assert errors[1] < 0.6 * errors[0] and errors[1] < 2.0 * errors[2]


def test_when_the_intrinsic_start_fails_the_output_of_the_maps_stands_and_the_report_says_why(remeshed_cow,
                                                                                               monkeypatch):
    from filter_symblend.auto import rounds
    from filter_symblend.errors import GeometryError

    def fails(*args):
        raise GeometryError("the intrinsic pairs fall\napart")

    weights = synthetic.limb_weights(remeshed_cow.points, **synthetic.LIMBS["cow"])
    deformed = synthetic.random_rigid(synthetic.articulate_limb(remeshed_cow.points, weights, 0.9), seed=7)
    monkeypatch.setattr(rounds, "_intrinsic_first_output", fails)
    with warnings.catch_warnings():
        warnings.simplefilter("error", SymblendWarning)  # nothing is said to rest on the intrinsic mirror
        result = symmetrize(deformed, faces=remeshed_cow.faces, pairs="auto", mode="articulated")
    tried = result.report.auto_pairs.intrinsic_start
    assert tried["kept"] == "maps" and tried["failed"] == "the intrinsic pairs fall apart"
    assert tried["because"].startswith("the rounds from the ") and "left a part asymmetric" in tried["because"]
    assert tried["maps_asymmetry"] == result.report.auto_pairs.output_asymmetry


def test_a_bend_in_articulated_mode_is_not_paired_twice(remeshed_cow):
    """Bent 0.6 rad, nothing is left asymmetric: the rounds from the map of space stand alone."""
    deformed = synthetic.random_rigid(synthetic.bend(remeshed_cow.points, 0.6), seed=7)
    report = symmetrize(deformed, faces=remeshed_cow.faces, pairs="auto", mode="articulated").report.auto_pairs
    assert report.output_asymmetry_p99 < AutoConfig().part_left_asymmetric and report.intrinsic_start is None


def _exact_cow_with_a_leg_swung(cow, angle):
    """(the cow's SurfaceTruth on its exact vertex twins, the cow posed with its leg swung ``angle`` rad, as in the
    corpus)."""
    from filter_symblend.testing.surface_truth import vertex_truth
    truth = vertex_truth(cow.points, cow.faces, cow.all_left, cow.all_right)
    weights = synthetic.limb_weights(truth.points, **synthetic.LIMBS["cow"])
    return truth, synthetic.random_rigid(synthetic.articulate_limb(truth.points, weights, angle), seed=7)


def test_the_growth_of_exact_vertex_pairs_follows_a_swung_leg_past_its_joint(cow):
    """The cow (exact vertex twins) with a leg swung 0.3 rad: the exact pairs grow from the body through the joint
    onto the leg, their local maps fitted to the eight nearest pairs (growth.GROWTH_NEIGHBOURS; fitted to twelve they
    stalled in the joint). Against ground truth the output's error over the true pairs: measured 0.108 -> 0.061 % of
    the diagonal, 100 landmark pairs 0.183 % (0.59x -> 0.33x)."""
    truth, deformed = _exact_cow_with_a_leg_swung(cow, 0.3)
    automatic = symmetrize(deformed, faces=truth.faces, pairs="auto", mode="articulated")
    alone = _landmarks_alone(deformed, *truth.landmarks(100), "articulated")
    errors = [truth.symmetry_error(p) for p in (deformed, automatic.points, alone.points)]
    print("cow, leg swung 0.3 rad, symmetry error before / automatic / 100 landmarks:", errors)
    assert errors[1] < 0.45 * errors[2]


def test_the_rounds_from_the_intrinsic_start_keep_its_pairs_on_a_limb_their_search_does_not_reach(cow, monkeypatch):
    """The cow (exact vertex twins) with a leg swung 0.9 rad: the rounds from a map of space leave the leg, so the
    rounds run again from the intrinsic start, whose pairs restore it. The next round's exact vertex growth pairs
    the body but not all of the leg; the intrinsic start's pairs there are kept beside its own (``carried``) and the
    round is kept. Without them the leg falls back toward its input pose in that round's solve, which is dropped as
    less symmetric (measured over the true pairs: 0.715 -> 0.703 % of the diagonal; the same kind of row in the
    corpus, swung 0.6 rad before the growth's smaller maps, 0.446 -> 0.342 %)."""
    from filter_symblend.auto import rounds
    truth, deformed = _exact_cow_with_a_leg_swung(cow, 0.9)

    def paired():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SymblendWarning)  # it rests on the intrinsic mirror, and says so
            result = symmetrize(deformed, faces=truth.faces, pairs="auto", mode="articulated")
        report = result.report.auto_pairs
        assert report.intrinsic_start["kept"] == "intrinsic"
        return [entry for entry in report.rounds if not entry.is_start], truth.symmetry_error(result.points)

    rounds_kept, error = paired()
    assert rounds_kept[0].kept and rounds_kept[0].carried > 0
    assert rounds_kept[0].to_dict()["carried"] == rounds_kept[0].carried
    monkeypatch.setattr(rounds, "keeping_unreached", lambda pairs, solved_from, surface: (pairs, 0))
    rounds_dropped, error_without = paired()
    print("cow, leg swung 0.9 rad, symmetry error with / without the carried pairs:", error, error_without)
    assert not rounds_dropped[0].kept and error < error_without


@pytest.fixture(scope="module")
def swung_limb(cow):
    """The cow with a hind leg swung 0.6 rad at its joint, posed, symmetrized by automatic pairs: the limb's
    symmetry error (over its true vertex pairs) before and after."""
    weights = synthetic.limb_weights(cow.points, **synthetic.LIMBS["cow"])
    deformed = synthetic.random_rigid(synthetic.articulate_limb(cow.points, weights, 0.6), seed=5)
    automatic = symmetrize(deformed, faces=cow.faces, pairs="auto", mode="articulated")
    limb = np.flatnonzero(weights[cow.all_left] > 0.5)
    before, after = (synthetic.symmetry_error(p, cow.all_left[limb], cow.all_right[limb])
                     for p in (deformed, automatic.points))
    print("limb swung 0.6 rad, the limb's symmetry error before / after:", before, after)
    return before, after


def test_a_swung_limb_is_followed_by_the_intrinsic_mirror(swung_limb):
    """No smooth mirror field follows a limb swung at a joint (the limb's error stayed as it was); the
    intrinsic mirror's pairs do, and the limb comes back more than halfway."""
    before, after = swung_limb
    assert after < 0.5 * before


@pytest.mark.xfail(strict=True, reason="a target missed (issue 33): the limb swung 0.6 rad comes back to about a "
                   "fifth of its error (measured 0.21), not a tenth: its joint is left partly unpaired "
                   "(docs/automatic-pairs.md)")
def test_a_swung_limb_comes_back_symmetric(swung_limb):
    before, after = swung_limb
    assert after < 0.1 * before


def test_the_intrinsic_mirrors_pairs_a_vertex_off_are_put_back_on_the_exact_twins():
    """A fifth of the pairs of an exactly symmetric mesh sent to a vertex next to the twin (as ZoomOut does on
    a thin limb): the robust local maps put all but a few back on the exact reflection."""
    from scipy.spatial import cKDTree
    from filter_symblend.auto.intrinsic_map import robust_twins
    points, _ = symmetric_blob(4)
    posed = synthetic.random_rigid(points, seed=2)
    twin = twins(points)
    tree = cKDTree(points)
    spacing = np.median(tree.query(points, k=2)[0][:, 1])
    rng = np.random.default_rng(0)
    wrong = rng.random(len(points)) < 0.2
    noisy = twin.copy()
    noisy[wrong] = tree.query(points, k=7)[1][twin[wrong], rng.integers(1, 7, np.count_nonzero(wrong))]
    assert np.linalg.norm(posed[noisy] - posed[twin], axis=1)[wrong].min() > 0.5 * spacing
    error = np.linalg.norm(robust_twins(posed, posed[noisy]) - posed[twin], axis=1)
    assert np.quantile(error, 0.99) < 1e-9 * spacing


def test_the_local_maps_shared_by_vertices_with_the_same_nearest_pairs_are_each_vertexs_own_fit():
    """A dense mesh between sparse pairs (here 1 vertex in 10, bent): each vertex's local map is fitted once per set
    of nearest pairs; it must be the map fitted to that vertex's own pairs, in their own order."""
    from scipy.spatial import cKDTree
    from filter_symblend.auto.growth import LOCAL_MAP_RIDGE, affine_mirror_maps, local_maps
    points, _ = symmetric_blob(4)
    bent = synthetic.bend(points, 0.6)
    partner = twins(points)
    paired = np.arange(0, len(points), 10)
    tree = cKDTree(bent[paired])
    predicted, rigid = local_maps(bent, partner, bent, paired, tree, AutoConfig())
    k = AutoConfig().local_neighbours
    own = paired[tree.query(bent, k=k)[1]]
    expected, expected_rigid = affine_mirror_maps(bent[own], bent[partner[own]], np.ones(own.shape), bent,
                                                  LOCAL_MAP_RIDGE)
    assert len(np.unique(np.sort(own, axis=1), axis=0)) < 0.8 * len(points)  # fits are shared
    np.testing.assert_allclose(predicted, expected, atol=1e-12 * np.ptp(points))
    np.testing.assert_allclose(rigid, expected_rigid, atol=1e-12)


def _growth_trying_every_source(surface, partner, eligible, twin_ok, config):
    """The growth as first written, every unpaired source near the pairs tried again each wave: the reference."""
    import dataclasses
    from scipy.spatial import cKDTree
    from filter_symblend.auto.growth import FRONTIER, GROWTH_NEIGHBOURS, RATIO, local_maps
    from filter_symblend.core.mesh_graph import one_pair_per_vertex
    points, waves = surface.points, 0
    config = dataclasses.replace(config, local_neighbours=GROWTH_NEIGHBOURS)  # the growth's own maps
    while True:
        paired = np.flatnonzero(partner >= 0)
        tree = cKDTree(points[paired])
        unpaired = np.flatnonzero(eligible & (partner < 0))
        sources = unpaired[np.isfinite(tree.query(points[unpaired], distance_upper_bound=FRONTIER * surface.spacing)[0])]
        predicted, rigid = local_maps(points, partner, points[sources], paired, tree, config)
        vertex, _, ratio = surface.nearest_vertices(predicted)
        back = surface.nearest_vertices(local_maps(points, partner, points[vertex], paired, tree, config)[0])[0]
        ok = (ratio <= RATIO) & (back == sources) & (partner[vertex] < 0) & twin_ok[vertex]
        ok &= np.einsum("nij,nj,ni->n", rigid, surface.normals[sources], surface.normals[vertex]) > 0
        sources, vertex = one_pair_per_vertex(sources[ok], vertex[ok])
        if not len(sources):
            return waves
        partner[sources], partner[vertex] = vertex, sources
        waves += 1


def test_the_growth_tries_a_failed_source_again_only_when_a_new_pair_comes_within_reach_of_its_maps(
        remeshed_cow, monkeypatch):
    """On a surface whose vertices have no exact twins the growth creeps from chance seeds, a few pairs a wave;
    a source that failed is skipped until a new pair could change its maps. The pairs and waves must be those of
    the growth that tries every source every wave, for fewer local maps."""
    from filter_symblend.auto import growth
    from filter_symblend.auto.surface import Surface
    points = synthetic.bend(remeshed_cow.points, 0.6)
    surface, config = Surface(points, remeshed_cow.faces), AutoConfig()
    vertex, distance, _ = surface.nearest_vertices(synthetic.bend(remeshed_cow.points * [-1.0, 1.0, 1.0], 0.6))
    mutual = vertex[vertex] == np.arange(len(points))
    seeds = np.flatnonzero(mutual & (distance < 0.1 * surface.local_spacing))  # chance near-twins
    partner = np.full(len(points), -1)
    partner[seeds] = vertex[seeds]
    everywhere = np.ones(len(points), dtype=bool)
    queried = []  # the sources and vertices each growth fitted local maps for
    original = growth._local_maps
    monkeypatch.setattr(growth, "_local_maps", lambda p, q, queries, *a: queried.append(len(queries)) or
                        original(p, q, queries, *a))
    expected = partner.copy()
    expected_waves = _growth_trying_every_source(surface, expected, everywhere, everywhere, config)
    reference_queries, queried[:] = sum(queried), []
    waves = growth.grow(surface, partner, everywhere, everywhere, everywhere, config)
    assert expected_waves >= 5 and 4 <= len(seeds) < 0.1 * np.count_nonzero(expected >= 0)  # it crept from them
    assert waves == expected_waves
    np.testing.assert_array_equal(partner, expected)
    assert sum(queried) < 0.5 * reference_queries


def test_the_parts_of_a_body_of_revolution_decide_its_mirror_plane():
    """Every plane through the axis mirrors the body; only y = 0 mirrors the knob and the ridge too."""
    points, faces = synthetic.body_with_two_parts()
    twins(points[:, [1, 0, 2]])  # exactly symmetric across y = 0 (twins asserts it across x = 0)
    posed = synthetic.random_rigid(points, seed=11)
    rotation = np.linalg.lstsq(np.column_stack([points, np.ones(len(points))]), posed, rcond=None)[0][:3].T
    result = symmetrize(posed, faces=faces, pairs="auto")
    diagonal = np.linalg.norm(np.ptp(points, axis=0))
    cosine = abs(np.dot(result.report.plane.normal, rotation @ [0.0, 1.0, 0.0]))
    assert cosine > np.cos(np.radians(0.1))
    assert np.abs(result.points - posed).max() < 1e-6 * diagonal


@pytest.mark.parametrize("angle", [0.6, pytest.param(1.2, marks=pytest.mark.xfail(strict=True, reason=(
    "a target missed (issue 46): bent 1.2 rad, the tessellation's mirror across the bending plane, which swaps the "
    "knob and the ridge, is grown again at the end of the search from the map that mirrors the most, which follows "
    "that plane")))])
def test_a_bent_body_of_revolution_is_paired_across_the_plane_its_parts_keep(angle):
    """The body of revolution with a knob and a ridge, bent toward its mirror's normal: the bent body is also
    mirror-symmetric across its bending plane, which swaps the knob and the ridge, and its icosphere's tessellation
    mirrors itself across that plane. That tessellation mirror, grown from the planes, paired every vertex wrongly
    and ended the search (its own share, 99.9 %, says nothing: its twins are vertices); a smooth field through its
    twins mirrors 95 % (smoothed_coverage), under field_suffices, so the search goes on and the plane the parts keep
    is found (bent 0.6 rad, measured: every twin right, the output's symmetry error 0 from 4.5 % of the diagonal;
    before, none right and 4.6 %)."""
    points, faces = synthetic.body_with_two_parts()
    points = points[:, [1, 0, 2]]  # its mirror plane x = 0, the knob on +y, the ridge on -y
    twin = twins(points)
    left = np.flatnonzero(points[:, 0] > 1e-9)
    bent = synthetic.random_rigid(synthetic.bend(points, angle), seed=7)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SymblendWarning)
        result = symmetrize(bent, faces=faces, pairs="auto", mode="affine")
    diagonal = np.linalg.norm(np.ptp(bent, axis=0))
    reported, _ = result.mirror_pairs.per_vertex()
    right = np.linalg.norm(reported[left] - bent[twin[left]], axis=1) < 0.01 * diagonal
    before, after = (synthetic.symmetry_error(p, left, twin[left]) for p in (bent, result.points))
    print(f"bent {angle} rad: twins right {right.mean():.3f}, symmetry error {before:.4g} -> {after:.4g}")
    assert right.mean() > 0.95 and after < 0.05 * before


def test_the_intrinsic_mirror_of_an_exactly_symmetric_mesh_is_its_mirror_in_any_pose():
    """The Laplace-Beltrami map sees no pose: posed anyhow, the bumpy blob's intrinsic mirror sends every
    vertex to its exact twin."""
    points, faces = symmetric_blob(4)
    posed = synthetic.random_rigid(points, seed=3)
    mesh = working_mesh(posed, faces, np.ones(len(points), dtype=bool), AutoConfig())
    twin = candidate_mirrors(mesh, AutoConfig())[0].vertex_map  # the one that reverses the most of the surface
    assert mesh.vertex_of.min() >= 0
    np.testing.assert_array_equal(mesh.points[twin[mesh.vertex_of]], posed[twins(points)])


def _blob_with_a_patch_mapped_onto_itself():
    """The bumpy blob, its exact mirror map, and that map with a patch on one side sent onto itself (as ZoomOut
    folds a limb onto itself), the patch's vertices (bool)."""
    points, faces = symmetric_blob(4)
    exact = twins(points)
    centre = points[np.argmax(points[:, 0] + 0.3 * points[:, 1])]
    patch = np.linalg.norm(points - centre, axis=1) < 0.35 * np.ptp(points[:, 0])
    folded = np.where(patch, np.arange(len(points)), exact)
    return points, faces, exact, folded, patch


def test_a_patch_a_map_sends_onto_itself_is_mapped_by_the_candidate_that_joins_the_rest():
    """The folded patch tears from the body mapped across; the exact map's twins of its border join the folded
    map's twins across the border, so the patch takes them: the exact mirror everywhere, from that row only."""
    points, faces, exact, folded, patch = _blob_with_a_patch_mapped_onto_itself()
    _, mass = cotangent_laplacian(points, faces)
    assert 20 < patch.sum() < 0.2 * len(points)
    identity = np.arange(len(points))
    mended, source = mended_map(points, faces, folded, np.array([identity, exact]), mass)
    np.testing.assert_array_equal(mended, exact)
    assert (source[patch] == 1).all() and set(np.unique(source)) <= {-1, 1}


def test_a_patch_no_candidate_joins_is_left_as_it_is():
    """The identity does not land beside the twins of the patch's border (and with no other candidate there is
    nothing to take): nothing is replaced."""
    points, faces, exact, folded, patch = _blob_with_a_patch_mapped_onto_itself()
    _, mass = cotangent_laplacian(points, faces)
    identity = np.arange(len(points))
    for others in (identity[None], np.empty((0, len(points)), dtype=np.int64)):  # one that does not join; none
        mended, source = mended_map(points, faces, folded, others, mass)
        np.testing.assert_array_equal(mended, folded)
        assert (source == -1).all()


@pytest.mark.corpus
def test_a_posed_mans_feet_mapped_onto_themselves_are_mended_from_a_candidate_that_swaps_them(bcicp):
    """On public ground truth (the BCICP dataset, read in place; skipped without it): TOSCA's david1, legs apart.
    The best intrinsic candidate folds each foot onto itself (83 % of the published twin pairs within 0.05
    sqrt(area), measured); its feet mapped as the candidates that join the legs there, the map mirrors more of the
    surface and is chosen, with 90 % (docs/benchmarks.md)."""
    from benchmarks.mirror_maps import surface_area, twin_errors
    points, faces, a, b = bcicp.shape("TOSCA", "david1")
    mesh = working_mesh(points, faces, np.ones(len(points), dtype=bool), AutoConfig())
    assert len(mesh.points) == len(points)  # no coarsening: the working mesh is the shape
    mirrors = candidate_mirrors(mesh, AutoConfig())
    scale = np.sqrt(surface_area(points, faces))
    right = {mirror.name: np.mean(twin_errors(points[mirror.vertex_map], points, a, b, scale) <= 0.05)
             for mirror in mirrors}
    print({name: round(float(share), 3) for name, share in right.items()})
    chosen, unmended = mirrors[0], next(mirror for mirror in mirrors if not mirror.mended_from)
    assert chosen.mended_from and chosen.mirrored_share > unmended.mirrored_share
    assert right[unmended.name] < 0.85 < right[chosen.name]


@pytest.mark.skipif(not (SHARED_DATA / "spot.obj").exists(), reason="../shared/data/spot.obj is absent")
def test_a_plane_that_leaves_a_swung_leg_unmirrored_does_not_end_a_posed_bodys_search():
    """Spot remeshed (no vertex keeps an exact twin) with a leg swung 0.3 rad: its best plane mirrors 96-97 % of
    it, which ends the search on a rigid scan (plane_suffices) but not on a posed body (field_suffices): the
    intrinsic mirror, which follows the leg, is tried and chosen, and the output is more symmetric than 100
    ground-truth landmark pairs make it (measured 0.73x; 1.48x when the plane ended the search)."""
    truth = remeshed_ground_truth(SHARED_DATA / "spot.obj", 2.0)
    weights = synthetic.limb_weights(truth.points, **synthetic.LIMBS["spot"])
    swung = synthetic.random_rigid(synthetic.articulate_limb(truth.points, weights, 0.3), seed=7)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SymblendWarning)
        result = symmetrize(swung, faces=truth.faces, pairs="auto", mode="articulated")
        landmarks = symmetrize(swung, *truth.landmarks(100), mode="articulated")
    shares, config = result.report.auto_pairs.coverage, AutoConfig()
    planes = max(shares["mirror plane"], shares["whitened mirror plane"])
    print("shares:", shares)
    assert config.plane_suffices <= planes < config.field_suffices <= shares["intrinsic mirror"]
    after, with_landmarks = truth.symmetry_error(result.points), truth.symmetry_error(landmarks.points)
    print("symmetry error, automatic / 100 landmark pairs:", after, with_landmarks)
    assert after < with_landmarks


@pytest.mark.skipif(not (SHARED_DATA / "spot.obj").exists(), reason="../shared/data/spot.obj is absent")
def test_exact_vertex_pairs_found_under_a_plane_are_the_reported_twins():
    """Spot (its tessellation mirrors itself) with a leg swung 0.3 rad, in standard mode (in articulated mode the
    search goes on past the plane and finds the tessellation's own mirror): a plane mirrors enough of it to be the
    map, and the rounds' pair search grows exact vertex pairs over the whole surface, the leg included, so the
    output is exact. The twins reported follow those pairs, not the points the plane predicts: on the leg those
    were 2 % of the diagonal or more off for 3.4 % of the vertices, about half of them confident."""
    from conftest import load_ground_truth
    spot = load_ground_truth(SHARED_DATA / "spot.obj")
    weights = synthetic.limb_weights(spot.points, **synthetic.LIMBS["spot"])
    swung = synthetic.random_rigid(synthetic.articulate_limb(spot.points, weights, 0.3), seed=7)
    result = symmetrize(swung, faces=spot.faces, pairs="auto", mode="standard")
    report = result.report.auto_pairs
    print(report.mirror_map.map)
    assert report.mirror_map.map.startswith("exact vertex pairs under the")
    twin, confidence = result.mirror_pairs.per_vertex()
    off = np.linalg.norm(twin[spot.all_left] - swung[spot.all_right], axis=1) / np.linalg.norm(np.ptp(swung, axis=0))
    print("twins within 1 % of the diagonal:", np.mean(off < 0.01))
    assert np.mean(off < 0.01) > 0.99 and not np.any((confidence[spot.all_left] >= 0.5) & (off > 0.02))
