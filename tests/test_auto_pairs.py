"""Automatic pairs: exact on exactly symmetric shapes, better than landmarks on deformed ones, real meshes as
they come (pieces, seams, a cropped side, a flat shape, a point cloud), refusals, clear errors."""

import warnings

import numpy as np
import pymeshlab
import pytest
from scipy.spatial import cKDTree

import filter_symblend  # noqa: F401  (binds the filter)
from filter_symblend import (GeometryError, LandmarkError, ParameterError, SymblendError, SymblendWarning,
                             SymmetryNotFoundError, symmetrize)
from filter_symblend.auto import AutoConfig
from filter_symblend.auto.maps import plane_map
from filter_symblend.auto.surface import Surface
from filter_symblend.auto.twins import covered_by, find_twins
from filter_symblend.core.mesh_quantities import mean_spacing, vertex_normals
from filter_symblend.core.mirror_fill import closest_points_on_surface
from filter_symblend.measures.surface_asymmetry import mirror_asymmetry
from filter_symblend.testing import synthetic

from conftest import SAMPLE_MESHES, SHARED_DATA, load_ground_truth, meshset_with_pairs, symmetric_blob, twins

pytestmark = pytest.mark.auto  # every test here runs automatic pairs, or tests a part of them

TARGET = 0.2  # the target: at most a fifth of the symmetry error of 100 landmark pairs


@pytest.fixture(scope="module")
def blob():
    return symmetric_blob(4)


def _quiet_symmetrize(*args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SymblendWarning)
        return symmetrize(*args, **kwargs)


def test_an_exactly_symmetric_mesh_in_any_pose_comes_back_unchanged(blob):
    points, faces = blob
    diagonal = np.linalg.norm(np.ptp(points, axis=0))
    for seed, mode in ((1, "standard"), (2, "affine")):
        posed = synthetic.random_rigid(points, seed)
        rotation = np.linalg.lstsq(np.column_stack([points, np.ones(len(points))]), posed, rcond=None)[0][:3].T
        result = symmetrize(posed, faces=faces, pairs="auto", mode=mode)
        assert np.abs(result.points - posed).max() < 1e-6 * diagonal
        angle = np.degrees(np.arccos(min(1.0, abs(np.dot(result.report.plane.normal, rotation @ [1.0, 0, 0])))))
        assert angle < 0.1
        auto = result.report.auto_pairs
        assert auto.twins_are == "exact vertices" and auto.midline_count > 0
        # its first map pairs every vertex: one round, with every pair at once (more than round_pairs)
        assert len(auto.rounds) == 1 and not auto.rounds[0].final
        assert auto.rounds[0].pairs == auto.pair_count > AutoConfig().round_pairs


def test_a_plane_gives_an_exactly_symmetric_mesh_its_exact_mirror_vertices(blob):
    points, faces = blob
    surface = Surface(points, faces)
    twins_found = find_twins(plane_map(surface, [1.0, 0.0, 0.0], 0.0), surface.usable_index, 1e-9)
    exact = twins_found.exact_vertex(1e-9)
    assert exact.all()
    np.testing.assert_array_equal(twins_found.vertex, twins(points)[surface.usable_index])
    off_plane = np.abs(points[surface.usable_index, 0]) > 1e-9
    np.testing.assert_array_equal(twins_found.side[off_plane], np.sign(points[surface.usable_index, 0])[off_plane])


def test_a_maps_coverage_is_what_its_twins_cover(blob):
    # covered_by scores every candidate map without the nearest vertices find_twins also finds: the same answer
    points, faces = blob
    surface = Surface(points, faces)
    tolerance = 0.01 * surface.diagonal
    for normal in ([1.0, 0.2, 0.0], [1.0, 0.0, 0.5]):  # tilted planes: some vertices mirrored, some not
        mirror = plane_map(surface, np.array(normal) / np.linalg.norm(normal), 0.0)
        covered = covered_by(mirror, surface.usable_index, tolerance)
        np.testing.assert_array_equal(covered, find_twins(mirror, surface.usable_index, tolerance).covered(tolerance))
        assert 0.05 < covered.mean() < 0.95


@pytest.fixture(scope="module")
def cow_100_landmarks(cow):
    return cow.landmarks(100)


def _against_landmarks(truth, deformed, landmarks, mode="affine"):
    """(auto result, symmetry error over every true pair of: auto, 100 landmarks; shape error of both)."""
    automatic = symmetrize(deformed, faces=truth.faces, pairs="auto", mode=mode)
    alone = _quiet_symmetrize(deformed, *landmarks, mode=mode)
    errors = [synthetic.symmetry_error(out, truth.all_left, truth.all_right) for out in (automatic.points, alone.points)]
    shapes = [synthetic.shape_error(out, truth.points) for out in (automatic.points, alone.points)]
    return automatic, errors, shapes


@pytest.mark.parametrize("deformation", ["bend 0.6 rad", "Figure 1"])
def test_a_bent_or_bent_and_compressed_cow_beats_100_landmarks_five_times(cow, cow_100_landmarks, deformation):
    deform = {"bend 0.6 rad": lambda p: synthetic.bend(p, 0.6), "Figure 1": synthetic.figure_1_deformation}[deformation]
    deformed = synthetic.random_rigid(deform(cow.points), seed=7)
    automatic, errors, shapes = _against_landmarks(cow, deformed, cow_100_landmarks)
    print(deformation, "symmetry error auto / 100 landmarks:", errors, "shape:", shapes)
    assert errors[0] < TARGET * errors[1]
    assert shapes[0] <= shapes[1]
    assert automatic.report.auto_pairs.twins_are == "exact vertices"


@pytest.mark.corpus
def test_a_strongly_bent_mirrored_tessellation_comes_back_exactly_symmetric():
    """Spot's triangles mirror each other: bent by 1.2 rad, its tessellation's own mirror map pairs every
    vertex with its true twin, where the geometric maps alone do not reach half the surface."""
    path = SHARED_DATA / "spot.obj"
    if not path.exists():
        pytest.skip(f"{path} is absent (shared test data not available)")
    spot = load_ground_truth(path)
    deformed = synthetic.random_rigid(synthetic.bend(spot.points, 1.2), seed=7)
    result = symmetrize(deformed, faces=spot.faces, pairs="auto", mode="affine")
    assert synthetic.symmetry_error(result.points, spot.all_left, spot.all_right) < 1e-9


@pytest.mark.parametrize("angle", [0.6, pytest.param(1.2, marks=pytest.mark.xfail(
    strict=True, reason="a target missed (issue 33): bent 1.2 rad in this pose, the best map mirrors 91 % of the "
    "pieces within 1 % but pairs them wrongly, and the output is less symmetric than the input (in the corpus "
    "benchmark's pose the same mesh comes back exact)"))])
def test_several_pieces_each_paired_with_its_mirror_piece_or_itself(angle):
    """Five separate closed pieces (a body, a lid and a spout on the plane, two ears each other's mirror
    image), bent: the pieces come back symmetric, the ears with each other."""
    points, faces = synthetic.several_pieces(3)
    offset, partner = synthetic.mirror_partners(points)
    left = np.flatnonzero((partner >= 0) & (points[:, 0] > offset))
    bent = synthetic.random_rigid(synthetic.bend(points, angle), seed=3)
    result = symmetrize(bent, faces=faces, pairs="auto", mode="affine")
    before, after = (synthetic.symmetry_error(p, left, partner[left]) for p in (bent, result.points))
    ears = np.flatnonzero(np.linalg.norm(points - [0.95, 0.55, -0.3], axis=1) < 0.3)
    ear_error = synthetic.symmetry_error(result.points, ears, partner[ears])
    print("symmetry error before / after, ears after:", before, after, ear_error)
    assert np.isfinite(result.points).all()
    assert after < 0.02 * before and ear_error < 0.02 * before


def test_a_cropped_side_pairs_only_where_a_counterpart_exists(cow):
    """The cow with 40 % of one side cut away, bent: where both sides exist it comes back symmetric, and
    what lost its counterpart follows the warp."""
    span = cow.points[:, 0].max() - cow.offset
    keep = cow.points[:, 0] > cow.offset - 0.6 * span
    cut, cut_faces, kept = synthetic.cropped(cow.points, cow.faces, keep)
    bent = synthetic.bend(cut, 0.3)
    result = symmetrize(bent, faces=cut_faces, pairs="auto", mode="affine")
    index = np.full(len(cow.points), -1)
    index[kept] = np.arange(len(kept))
    twin = np.maximum(cow.partner, 0)
    both = np.flatnonzero(keep & (cow.partner >= 0) & keep[twin] & (cow.points[:, 0] > cow.offset))
    left, right = index[both], index[twin[both]]
    before, after = (synthetic.symmetry_error(p, left, right) for p in (bent, result.points))
    print("symmetry error where both sides exist, before / after:", before, after)
    assert np.isfinite(result.points).all() and after < 0.05 * before
    alone = index[np.flatnonzero(keep & ~keep[twin])]  # vertices whose counterpart was cut away
    moved = np.linalg.norm(result.points[alone] - bent[alone], axis=1).max()
    assert moved < 0.2 * np.linalg.norm(np.ptp(cut, axis=0))  # they follow, they do not fly off


def test_duplicated_vertices_move_with_their_originals(blob):
    points, faces = blob
    seamed, seamed_faces = synthetic.with_seams(points, faces, points[faces].mean(axis=1)[:, 2] > 0.2)
    copies = len(seamed) - len(points)
    original = np.unique(faces[points[faces].mean(axis=1)[:, 2] > 0.2])
    bent = synthetic.bend(seamed, 0.3)
    result = symmetrize(bent, faces=seamed_faces, pairs="auto", mode="affine")
    assert copies > 100
    np.testing.assert_array_equal(result.points[len(points):], result.points[original])
    twin = twins(points)
    left = np.flatnonzero(points[:, 0] > 1e-9)
    assert synthetic.symmetry_error(result.points, left, twin[left]) < 0.05 * synthetic.symmetry_error(bent, left, twin[left])


@pytest.mark.parametrize("sampling", ["mirrored", "independent"])
def test_a_flat_shape_is_symmetrized_in_its_plane(sampling):
    """A flat, nearly mirror-symmetric region (z = 0) whose outline's right side bulges by up to 0.04, its
    two sides sampled as mirror images or independently (a traced drawing), in every mode: the output stays
    exactly flat and its outline's asymmetry drops to under half."""
    angle = (np.linspace(0, 2 * np.pi, 120, endpoint=False) if sampling == "mirrored"
             else np.sort(np.random.default_rng(1).uniform(0, 2 * np.pi, 120)))
    radius = 1.0 + 0.3 * np.cos(2 * angle) + 0.15 * np.cos(3 * angle)  # even in x -> -x (angle -> pi - angle)
    outline = np.column_stack([radius * np.sin(angle), radius * np.cos(angle)])
    outline[:, 0] += 0.04 * np.sin(5 * angle) ** 2 * (outline[:, 0] > 0)
    points, faces = synthetic.flat_region(outline)

    def outline_asymmetry(outline, normal, offset):
        """Largest distance from an outline vertex's mirror image to the outline (a closed polyline)."""
        along = np.linspace(0.0, 1.0, 50, endpoint=False)[:, None, None]
        dense = (outline + along * (np.roll(outline, -1, axis=0) - outline)).reshape(-1, 3)
        reflected = outline - 2.0 * (outline @ normal - offset)[:, None] * normal
        return cKDTree(dense).query(reflected)[0].max()

    before = outline_asymmetry(points[:120], np.array([1.0, 0.0, 0.0]), 0.0)
    for mode in ("standard", "affine", "articulated"):
        result = symmetrize(points, faces=faces, pairs="auto", mode=mode)
        assert (result.points[:, 2] == 0.0).all()
        plane_normal = np.asarray(result.report.plane.normal)
        assert abs(plane_normal[2]) < 1e-12  # the mirror line lies in the plane
        after = outline_asymmetry(result.points[:120], plane_normal, result.report.plane.offset)
        print(mode, "outline asymmetry before / after:", before, after)
        assert after < 0.5 * before


def test_an_outline_ratio_has_a_surface_ratios_chance():
    """Random points near a straight polyline and near a triangulated plane: the share passing the ratio test
    on the plane equals the share passing the outline's chance-mapped ratio test (within sampling error)."""
    from filter_symblend.auto.surface import Outline
    rng = np.random.default_rng(0)
    grid = np.stack(np.meshgrid(np.arange(40.0), np.arange(40.0)), axis=-1).reshape(-1, 2)
    lattice = np.column_stack([grid[:, 0] + 0.5 * (grid[:, 1] % 2), grid[:, 1] * np.sqrt(3) / 2])  # spacing 1
    drops = rng.uniform([10, 10], [30, 30], size=(20000, 2))
    distance = cKDTree(lattice).query(drops, k=2)[0]
    on_surface = np.mean(distance[:, 0] / distance[:, 1] <= 0.5)
    line = np.arange(100.0)[:, None]
    distance = cKDTree(line).query(rng.uniform(10, 90, size=(20000, 1)), k=2)[0]
    on_outline = np.mean(Outline.chance_ratio(distance[:, 0] / distance[:, 1]) <= 0.5)
    print("share passing on a surface / on an outline (mapped):", on_surface, on_outline)
    assert abs(on_surface - on_outline) < 0.05


def test_flat_neighbourhoods_of_automatic_pairs_widen_theta(blob):
    """A theta_width too narrow for the local stretch around automatic pairs (which the user did not place)
    is doubled until it fits, and said in the report; with the user's own landmarks it is an error."""
    points, faces = blob
    bent = synthetic.bend(points, 0.3)
    result = symmetrize(bent, faces=faces, pairs="auto", mode="affine", theta_width=0.5)
    widths = {entry.raised_widths.get("theta_width") for entry in result.report.auto_pairs.rounds}
    assert widths == {1.0}
    twin = twins(points)
    left = np.flatnonzero(points[:, 0] > 1e-9)
    assert synthetic.symmetry_error(result.points, left, twin[left]) < 0.05 * synthetic.symmetry_error(bent, left, twin[left])
    pairs = left[:: max(1, len(left) // 200)]
    with pytest.raises(GeometryError, match=r"are \(nearly\) coplanar, so the local stretch .* Increase `theta_width`"):
        symmetrize(bent, pairs, twin[pairs], mode="affine", theta_width=0.5)


def test_pieces_far_apart_are_connected_by_a_raised_phi_width():
    """Two mirror-symmetric pieces twelve diameters apart: the automatic pairs of each fall apart into two
    groups at the default phi_width, which is raised to the width that connects them and said in the report (the
    exact vertex pairs cover both pieces: they come back exactly symmetric); with the user's own landmarks it is an
    error naming that width."""
    from filter_symblend.parameters import DEFAULTS

    points, faces = synthetic.icosphere(3)
    points = synthetic.bumpy(points)
    partner = synthetic.mirror_partners(points)[1]
    pieces = np.vstack([points, points + [0.0, 0.0, 12.0]])
    partners = np.concatenate([partner, partner + len(points)])
    bent = synthetic.bend(pieces, 0.3)
    result = symmetrize(bent, faces=np.vstack([faces, faces + len(points)]), pairs="auto", mode="affine")
    raised = [entry.raised_widths["phi_width"] for entry in result.report.auto_pairs.rounds
              if "phi_width" in entry.raised_widths]
    assert raised and min(raised) > 2 * DEFAULTS["phi_width"]  # measured 21.2 spacings
    left = np.flatnonzero(pieces[:, 0] > 0.05)
    before, after = (synthetic.symmetry_error(p, left, partners[left]) for p in (bent, result.points))
    assert after < 1e-9 * before
    pairs = left[::40]
    with pytest.raises(GeometryError, match=rf"fall apart into 2 groups at `phi_width` = {DEFAULTS['phi_width']:g}: "
                                            r".* Set `phi_width` to [0-9.]+ or more"):
        symmetrize(bent, pairs, partners[pairs], mode="affine")


def test_a_point_cloud_without_faces_is_paired_by_its_points(blob):
    points, _ = blob
    posed = synthetic.random_rigid(points, 5)
    result = symmetrize(posed, pairs="auto")
    assert np.abs(result.points - posed).max() < 1e-6 * np.linalg.norm(np.ptp(points, axis=0))
    assert result.report.auto_pairs.twins_are == "exact vertices"


def test_a_shape_without_mirror_symmetry_is_refused_saying_how_much_mirrors():
    """pymeshlab's bunny: half of its surface lies within half a percent of its mirror image, the rest (ears,
    head) far from it; and the mirror its spectrum offers does not keep its heat kernel signatures."""
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(SAMPLE_MESHES / "bunny.obj"))
    ms.meshing_decimation_quadric_edge_collapse(targetfacenum=10000)
    mesh = ms.current_mesh()
    with pytest.raises(SymmetryNotFoundError, match=r"No mirror symmetry found: the best mirror map \(.+\) mirrors "
                       r"\d+% of the surface within 1% of its size but \d+% within 0.25%, where a field fitted onto the "
                       r"surface lands on a symmetric shape \(mirror plane \d+%.*needs 65% there\. Its intrinsic "
                       r"mirror does not keep the shape's heat kernel signatures \(disagreement 0\.\d\d, a symmetric "
                       r"shape 0\.08 or less\): the shape has no intrinsic mirror symmetry\. Place landmark pairs and "
                       r"use pairs='landmarks'") as raised:
        symmetrize(mesh.vertex_matrix(), faces=mesh.face_matrix(), pairs="auto", mode="articulated")
    assert isinstance(raised.value, GeometryError)  # a SymblendError, a ValueError
    with pytest.raises(SymmetryNotFoundError, match=r"needs 65% there\. If it is a posed body, mode='articulated' "
                       r"pairs it by its intrinsic mirror\. Place landmark pairs"):
        symmetrize(mesh.vertex_matrix(), faces=mesh.face_matrix(), pairs="auto")


def test_a_map_that_mirrors_too_little_is_refused_with_every_share_listed(blob):
    """A noisy point cloud of the blob (no tessellation to mirror): its best plane mirrors about 78 % of it.
    Asked for 99 % the run is refused, naming the best map and every share tried, the same shares the
    accepted run reports at the default 75 %."""
    points = blob[0] + np.random.default_rng(1).normal(scale=0.015, size=blob[0].shape)
    plane_first = dict(plane_suffices=0.5)  # the planes' share decides, before any registered field
    accepted = _quiet_symmetrize(points, pairs="auto", auto_config=AutoConfig(**plane_first))
    shares = accepted.report.auto_pairs.coverage
    assert accepted.report.auto_pairs.mirror_map.map == "mirror plane" and 0.75 <= shares["mirror plane"] < 0.99
    listed = ", ".join(f"{name} {share:.0%}" for name, share in shares.items())
    with pytest.raises(SymmetryNotFoundError, match=rf"^No mirror symmetry found: the best mirror map \(mirror plane\) "
                       rf"mirrors {shares['mirror plane']:.0%} of the surface within 1% of its size \({listed}\); a "
                       r"mirror-symmetric shape, even bent or compressed, needs 99%\. If it is a posed body"):
        _quiet_symmetrize(points, pairs="auto", auto_config=AutoConfig(min_coverage=0.99, **plane_first))


def _corpus():
    """Every mesh of ../shared/data and pymeshlab's samples but two, those above 4,000 faces simplified to
    2,000 (the corpus benchmark runs them whole)."""
    paths = sorted(SHARED_DATA.glob("*.obj"))  # igea.ply and pymeshlab's bunny have tests of their own
    paths += [SAMPLE_MESHES / name for name in ("cow.obj", "bone.ply", "airplane.obj", "cube.obj")]
    for path in paths:
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(path))
        if ms.current_mesh().face_number() > 4000:
            ms.meshing_decimation_quadric_edge_collapse(targetfacenum=2000)
        yield path.name, ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()


# What the corpus's READMEs say of each mesh: mirror-symmetric (exactly or as a scan), or not at all; the
# others (CAD parts, partly symmetric) may go either way but never give a non-finite output.
SYMMETRIC = {"cow.obj", "spot.obj", "homer.obj", "cheburashka.obj", "woody.obj"}
NOT_SYMMETRIC = {"stanford-bunny.obj"}


@pytest.mark.corpus
def test_every_corpus_mesh_is_symmetrized_or_refused_as_its_symmetry_says():
    outcomes = {}
    for name, points, faces in _corpus():
        try:
            result = symmetrize(points, faces=faces, pairs="auto")
        except SymblendError as error:
            outcomes[name] = f"refused: {error}"
            continue
        assert np.isfinite(result.points).all(), name
        assert result.points.shape == points.shape
        outcomes[name] = "ok"
    print(outcomes)
    assert len(outcomes) >= 4  # pymeshlab's four samples at least
    assert all(outcomes[name] == "ok" for name in SYMMETRIC & set(outcomes)), outcomes
    assert all(outcomes[name].startswith("refused: No mirror symmetry found") for name in NOT_SYMMETRIC & set(outcomes))


def test_a_singular_system_is_an_error_not_a_non_finite_output(blob, monkeypatch):
    """Whatever goes wrong inside the solve (here the global solve is made to return NaN), the caller gets
    a GeometryError, for landmarks and automatic pairs alike, never NaN coordinates."""
    from importlib import import_module
    core = import_module("filter_symblend.core.solve")
    points, faces = blob
    original = core.global_solve

    def broken(*args, **kwargs):
        r, s = original(*args, **kwargs)
        r[3] = np.nan
        return r, s

    monkeypatch.setattr(core, "global_solve", broken)
    left = np.flatnonzero(points[:, 0] > 0.1)[::10]
    with pytest.raises(GeometryError, match=r"The solve gave non-finite coordinates"):
        symmetrize(points, left, twins(points)[left])
    with pytest.raises(GeometryError, match=r"The solve gave non-finite coordinates"):
        symmetrize(synthetic.bend(points, 0.2), faces=faces, pairs="auto")


def test_the_config_documents_every_field_and_the_docs_show_its_table():
    import dataclasses
    import pathlib
    table = AutoConfig.describe()
    for field in dataclasses.fields(AutoConfig):
        assert f"`{field.name}`" in table and field.metadata["unit"] and len(field.metadata["reason"]) > 40
    docs = pathlib.Path(__file__).resolve().parents[1] / "docs" / "automatic-pairs.md"
    assert table.rstrip() in docs.read_text()


@pytest.mark.parametrize("deformation", ["bend", "figure 1"])
def test_landmarks_plus_auto_makes_every_vertex_pair_more_symmetric(cow, cow_100_landmarks, deformation):
    deform = {"bend": lambda p: synthetic.bend(p, 1.2), "figure 1": synthetic.figure_1_deformation}[deformation]
    deformed = synthetic.random_rigid(deform(cow.points), seed=3)
    left, right = cow_100_landmarks
    alone = _quiet_symmetrize(deformed, left, right, mode="affine")
    dense = _quiet_symmetrize(deformed, left, right, faces=cow.faces, pairs="landmarks+auto", mode="affine")
    error_alone = synthetic.symmetry_error(alone.points, cow.all_left, cow.all_right)
    error_dense = synthetic.symmetry_error(dense.points, cow.all_left, cow.all_right)
    print(deformation, "landmarks alone / with automatic pairs:", error_alone, error_dense)
    assert error_dense < error_alone / 2
    assert synthetic.shape_error(dense.points, cow.points) <= synthetic.shape_error(alone.points, cow.points)
    assert dense.report.landmark_asymmetry_after.max_relative < 1e-9  # the user's landmarks stay exact
    assert dense.report.pair_count == 100 and dense.report.auto_pairs.pair_count > 500


def _cow_with_a_subtle_dent(cow, depth=0.1):
    """The exactly symmetric cow with a patch of its left flank pushed out along the normals by ``depth``
    mean edge lengths. (points, patch mask, mirror twins of the patch, mean edge length)."""
    spacing = mean_spacing(cow.points, cow.faces)
    normals, _ = vertex_normals(cow.points, cow.faces)
    centre = cow.points[np.argmax(cow.points[:, 0])]
    patch = np.linalg.norm(cow.points - centre, axis=1) < 0.07 * cow.diagonal
    dented = cow.points.copy()
    dented[patch] += depth * spacing * normals[patch]
    twin = cow.partner[patch]
    return dented, patch, twin[twin >= 0], spacing


def test_excluded_vertices_do_not_pull_the_sound_side_toward_them(cow):
    dented, patch, twin, spacing = _cow_with_a_subtle_dent(cow)
    paired = symmetrize(dented, faces=cow.faces, pairs="auto", mode="affine")
    excluded = symmetrize(dented, faces=cow.faces, pairs="auto", mode="affine", auto_excluded=patch)
    moved = [np.linalg.norm(out.points[twin] - cow.points[twin], axis=1).max() / spacing for out in (paired, excluded)]
    print("sound twins moved (edges), paired / excluded:", moved)
    assert moved[1] < moved[0] / 10
    assert excluded.report.auto_pairs.excluded_vertices == np.count_nonzero(patch)


def test_excluded_vertices_as_a_mask_or_as_indices_are_the_same_problem(cow):
    from filter_symblend.parameters import ARRAYS, validate_parameters
    from filter_symblend.pipeline import build_problem

    options = validate_parameters({"pairs": "auto"}, ARRAYS)
    patch = cow.points[:, 1] > np.quantile(cow.points[:, 1], 0.9)
    for given in (patch, np.flatnonzero(patch)[::-1]):
        problem = build_problem(cow.points, options, faces=cow.faces, auto_excluded=given)
        np.testing.assert_array_equal(problem.excluded, np.flatnonzero(patch))


def test_a_missing_region_is_left_out_of_the_automatic_pairs_and_filled_from_the_sound_side(cow):
    dented, patch, twin, spacing = _cow_with_a_subtle_dent(cow)
    left, right = cow.landmarks(150)
    sound = ~patch[left] & ~patch[right]
    off_surface = {}
    for pairs in ("landmarks", "landmarks+auto"):
        ms = meshset_with_pairs(dented, cow.faces, left[sound], right[sound])
        ms.current_mesh().add_vertex_custom_scalar_attribute(np.where(patch, 0.0, 1.0), "symblend_weight")
        report = ms.generate_symmetrized_mesh(missing_region="weight", pairs=pairs, mode="affine")
        stored, output = ms.mesh(0).vertex_matrix(), ms.current_mesh().vertex_matrix()
        assert np.linalg.norm(output[twin] - stored[twin], axis=1).max() < 1e-2 * spacing
        on_surface = closest_points_on_surface(cow.points, cow.faces, output[patch])
        off_surface[pairs] = np.linalg.norm(on_surface - output[patch], axis=1) / spacing
    assert report["auto_pairs"]["excluded_vertices"] == np.count_nonzero(patch)
    assert off_surface["landmarks+auto"].mean() <= off_surface["landmarks"].mean() + 0.01
    assert off_surface["landmarks+auto"].max() <= off_surface["landmarks"].max() + 0.01


@pytest.mark.parametrize(("excluded", "pairs", "message"), [
    (np.ones(4, dtype=bool), "landmarks+auto", r"`auto_excluded` as a mask needs one entry per vertex \(2904\), got shape \(4,\)"),
    ([5000], "landmarks+auto", r"`auto_excluded` holds vertex 5000, but the mesh has vertices 0\.\.2903\."),
    ([-1], "landmarks+auto", r"`auto_excluded` holds vertex -1"),
    ([0.5], "landmarks+auto", r"`auto_excluded` must hold integer vertex indices, got float64 values\."),
    ([3], "landmarks", r"`auto_excluded` keeps vertices out of the automatic pairs, and pairs='landmarks' finds none"),
])
def test_bad_exclusions_are_refused_naming_the_fix(cow, excluded, pairs, message):
    left, right = cow.landmarks(20)
    with pytest.raises(SymblendError, match=message):
        symmetrize(cow.points, left, right, faces=cow.faces, pairs=pairs, auto_excluded=excluded)


@pytest.mark.parametrize(("faces", "message"), [
    (np.array([[0, 1, 2.5]]), r"`faces` must be an \(F, 3\) array of vertex indices, got shape \(1, 3\) of float64"),
    (np.array([[0, 1, 99]]), r"`faces` row 0 refers to vertex 99, but there are 10 vertices \(0\.\.9\)\."),
])
def test_bad_faces_are_refused_naming_the_row(faces, message):
    with pytest.raises(ParameterError, match=message):
        symmetrize(np.random.default_rng(0).normal(size=(10, 3)), faces=faces, pairs="auto")


def test_progress_covers_every_round(blob):
    points, faces = blob
    seen = []
    result = symmetrize(synthetic.bend(points, 0.3), faces=faces, pairs="auto",
                        progress=lambda percent, message: seen.append((percent, message)))
    percents = [percent for percent, _ in seen]
    assert percents == sorted(percents) and percents[-1] == 100.0
    rounds = [entry for entry in result.report.auto_pairs.rounds if not entry.final]
    assert rounds and all(any(f"round {k}" in message for _, message in seen) for k in range(1, len(rounds) + 1))
    assert not any(f"round {len(rounds) + 1}" in message for _, message in seen)


def test_auto_refuses_landmarks():
    with pytest.raises(LandmarkError, match=r"pairs='auto'.*ignores landmarks.*pairs='landmarks\+auto'"):
        symmetrize(np.eye(3), [0], [1], pairs="auto")


def test_landmark_modes_need_landmarks():
    with pytest.raises(LandmarkError, match=r"`pairs='landmarks\+auto'` needs landmark pairs.*pairs='auto'"):
        symmetrize(np.eye(3), pairs="landmarks+auto")


def test_too_few_pairable_vertices_are_refused():
    with pytest.raises(GeometryError, match=r"The mesh has 3 vertices that can be paired"):
        symmetrize(np.eye(3), pairs="auto")


@pytest.mark.parametrize(("value", "message"), [
    (2.5, r"`auto_pair_count` must be a whole number, got 2.5"),
    (5, r"`auto_pair_count` must be in 10..100000, got 5"),
    ("many", r"`auto_pair_count` must be a number, got 'many'"),
    (float("inf"), r"`auto_pair_count` must be finite, got inf"),
])
def test_integer_parameters_are_checked(value, message):
    with pytest.raises(ParameterError, match=message):
        symmetrize(np.eye(3), pairs="auto", auto_pair_count=value)


def test_auto_on_a_meshset_ignores_the_landmark_attributes(cow):
    left, right = cow.landmarks(30)
    ms = meshset_with_pairs(synthetic.random_rigid(cow.points, 2), cow.faces, left, right)
    ms.current_mesh().add_vertex_custom_scalar_attribute(np.full(len(cow.points), 0.5), "symblend_midline")
    report = ms.generate_symmetrized_mesh(pairs="auto")  # a bad midline attribute is not even read
    assert report["pair_count"] == 0  # no landmark pair: only automatic ones
    moved = np.abs(ms.current_mesh().vertex_matrix() - ms.mesh(report["input_mesh_id"]).vertex_matrix()).max()
    assert moved < 1e-6 * cow.diagonal  # exactly symmetric in, unchanged out


@pytest.mark.corpus
def test_the_igea_scan_is_made_symmetric_without_moving_more_than_its_asymmetry():
    path = SHARED_DATA / "igea.ply"
    if not path.exists():
        pytest.skip(f"{path} is absent (shared test data not available)")
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    ms.meshing_decimation_quadric_edge_collapse(targetfacenum=12000)
    points, faces = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    result = symmetrize(points, faces=faces, pairs="auto")
    before, after = mirror_asymmetry(points, faces), mirror_asymmetry(result.points, faces)
    p90 = [np.quantile(m["per_vertex"], 0.9) for m in (before, after)]
    print("90th percentile mirror distance before / after:", p90)
    assert p90[1] < 0.25 * p90[0]
    assert np.abs(result.points - points).max() < before["max"]


def _box(sides=(1.0, 2.0, 3.0)):
    """A box with these side lengths, midpoint-subdivided four times: three mirror planes, each exact."""
    ms = pymeshlab.MeshSet()
    ms.create_cube(size=1.0)
    ms.meshing_surface_subdivision_midpoint(iterations=4, threshold=pymeshlab.PercentageValue(0))
    return ms.current_mesh().vertex_matrix() * np.asarray(sides), ms.current_mesh().face_matrix()


def test_a_box_names_its_other_mirror_planes_and_its_confidence_says_so():
    """The three planes of a 1 x 2 x 3 box mirror all of it: one is paired, the other two are named as
    alternatives with a warning, and the confidence is low (the twins agree with both other planes only at the
    box's centre); the exactly symmetric box comes back unchanged."""
    points, faces = _box()
    posed = synthetic.random_rigid(points, seed=5)
    with pytest.warns(SymblendWarning, match=r"another mirror symmetry fits this shape about as well as the one "
                                             r"paired \(mirror plane, 100% of the surface mirrored\): mirror plane 2 "
                                             r"\(100%\), mirror plane 3 \(100%\)"):
        result = symmetrize(posed, faces=faces, pairs="auto")
    found = result.report.auto_pairs
    assert {"mirror plane 2", "mirror plane 3"} <= set(found.alternatives)
    assert all(share == 1.0 for share in found.alternatives.values())
    assert np.abs(result.points - posed).max() < 1e-6 * np.linalg.norm(np.ptp(points, axis=0))
    assert found.mirror_map.coverage == 1.0 and found.mirror_map.confident_share < 0.1


def test_the_pairs_command_writes_the_chosen_symmetrys_pairs_of_a_box_to_correct(tmp_path, capsys):
    """Nothing is confident on a box (three planes): `symblend pairs` still writes the chosen plane's pairs, each
    pair mirror images across it, and says that other symmetries fit as well."""
    from filter_symblend.commands.main import main
    from filter_symblend.landmarks.formats import read_landmarks
    points, faces = _box()
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(points, faces))
    ms.save_current_mesh(str(tmp_path / "box.ply"))
    assert main(["pairs", str(tmp_path / "box.ply"), "-o", str(tmp_path / "box.pp")]) == 0
    printed = capsys.readouterr()
    assert "box.pp: 20 automatic pairs (of 0 confident twins; map: exact vertex pairs under the mirror plane;" in printed.out
    assert "other symmetries mirror this shape about as well (mirror plane 2, mirror plane 3" in printed.err
    assert ("these pairs follow exact vertex pairs under the mirror plane, whatever their confidence; keep them, or "
            "move them") in printed.err
    named = {landmark.name: np.array(landmark.position) for landmark in read_landmarks(tmp_path / "box.pp").landmarks}
    left = np.array([named[f"L_auto_{k}"] for k in range(1, 21)])
    right = np.array([named[f"R_auto_{k}"] for k in range(1, 21)])
    flipped = np.abs(left - right) > 1e-9  # one coordinate changes sign, the same one for every pair
    assert np.all(flipped.sum(axis=1) == 1) and len(set(np.argmax(flipped, axis=1))) == 1
    np.testing.assert_allclose(np.abs(left), np.abs(right), atol=1e-9)


def test_a_rival_lowers_each_twins_confidence_by_how_far_it_puts_the_twin():
    """Two planes of the box, x = 0 chosen and y = 0 a rival: where the rival's twin lies d local spacings from
    the chosen twin, the agreement is exp(-d^2 / 2): 1 on the line where the planes meet."""
    from filter_symblend.auto.rivals import Rival, rival_agreement
    from filter_symblend.auto.surface import build_surface
    points, faces = _box()
    surface = build_surface(points, faces)
    chosen, rival = (plane_map(surface, normal, 0.0) for normal in np.eye(3)[:2])
    twins = chosen.predict(points)
    spacing = surface.local_spacing
    agreement = rival_agreement([Rival(rival, 1.0)], points, twins, spacing)
    expected = np.exp(-0.5 * (np.linalg.norm(points * [-1, 1, 1] - points * [1, -1, 1], axis=1) / spacing) ** 2)
    np.testing.assert_allclose(agreement, expected, rtol=1e-12)
    on_line = np.all(np.abs(points[:, :2]) < 1e-12, axis=1)
    assert on_line.any() and np.all(agreement[on_line] == 1.0) and np.all(agreement[np.abs(points[:, 1]) > 0.3] < 0.01)


def test_a_shape_with_one_mirror_plane_names_no_alternative(cow):
    result = symmetrize(synthetic.random_rigid(cow.points, seed=2), faces=cow.faces, pairs="auto")
    assert result.report.auto_pairs.alternatives == {}
    assert result.report.auto_pairs.mirror_map.confident_share > 0.9
    assert not any("another mirror symmetry" in message for message in result.report.warnings)


def test_a_rounds_pairs_keep_those_of_the_output_before_only_where_none_of_them_reaches(blob):
    """The pairs of the solve before are kept where no pair of the round comes within growth.FRONTIER spacings of
    either side (a region the round's search did not reach), and not elsewhere; the first round keeps none."""
    from filter_symblend.auto.growth import FRONTIER
    from filter_symblend.auto.pairs import AutomaticPairs, keeping_unreached
    from filter_symblend.auto.surface import build_surface
    from filter_symblend.core.surface_points import vertex_points
    points, faces = blob
    surface = build_surface(points, faces)
    twin = twins(points)
    left = np.flatnonzero((points[:, 0] > 1e-9) & (twin != np.arange(len(points))))
    height = points[left, 2]
    reached = left[height < np.quantile(height, 0.5)]  # the round's search paired the lower half
    before = left[::3]  # the solve before: every third pair, over both halves
    pairs_of = lambda vertices: AutomaticPairs(*vertex_points(vertices), *vertex_points(twin[vertices]),  # noqa: E731
                                               np.zeros(0, dtype=np.int64), None)
    pairs = pairs_of(reached)
    unchanged, none = keeping_unreached(pairs, None, surface)
    assert unchanged is pairs and none == 0
    joined, carried = keeping_unreached(pairs, pairs_of(before), surface)
    sides = np.vstack([points[reached], points[twin[reached]]])
    gap = np.min(np.linalg.norm(points[before][:, None] - sides[None], axis=2), axis=1)
    gap_twin = np.min(np.linalg.norm(points[twin[before]][:, None] - sides[None], axis=2), axis=1)
    far = before[(gap > FRONTIER * surface.spacing) & (gap_twin > FRONTIER * surface.spacing)]
    assert 0 < carried == len(far) < len(before) and np.all(points[far, 2] > np.quantile(height, 0.5))
    np.testing.assert_array_equal(joined.left_corners[:len(reached), 0], reached)
    np.testing.assert_array_equal(joined.left_corners[len(reached):, 0], far)
    np.testing.assert_array_equal(joined.right_corners[len(reached):, 0], twin[far])
