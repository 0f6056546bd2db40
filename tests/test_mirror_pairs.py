"""The mirror map as a result (issue 45): every vertex's twin, against the ground truth of a symmetric mesh
remeshed so that no vertex has an exact twin and deformed by a known map; and a confidence that finds the
twins a map gets wrong."""

import pathlib
import re

import numpy as np
import pytest

from filter_symblend import MirrorPairs, ParameterError, find_mirror_pairs
from filter_symblend.auto.confidence import mirror_pairs
from filter_symblend.auto.config import DEFAULT
from filter_symblend.auto.maps import MirrorMap, plane_map
from filter_symblend.auto.surface import build_surface
from filter_symblend.core.mirror_pairs import CONFIDENT
from filter_symblend.testing import synthetic
from conftest import symmetric_blob, twins

pytestmark = pytest.mark.auto


@pytest.fixture(scope="module")
def bent_remeshed_cow(remeshed_cow):
    deformed = synthetic.random_rigid(synthetic.bend(remeshed_cow.points, 0.6), seed=7)
    return remeshed_cow, deformed, find_mirror_pairs(deformed, remeshed_cow.faces, mode="affine")


def test_twins_of_a_bent_remeshed_cow_are_its_true_twins(bent_remeshed_cow):
    """Every vertex with a twin is listed (not only the solve's pairs), and the twins are the material
    points the ground truth names, to a small fraction of an edge."""
    truth, deformed, pairs = bent_remeshed_cow
    assert isinstance(pairs, MirrorPairs)
    twin, confidence = pairs.per_vertex()
    listed = np.isfinite(twin[truth.left]).all(axis=1)
    assert listed.mean() > 0.9  # far more than the few hundred pairs that enter the solve
    assert len(pairs.vertex) > 0.9 * len(deformed)
    spacing = np.median(np.linalg.norm(deformed[truth.faces[:, 0]] - deformed[truth.faces[:, 1]], axis=1))
    error = np.linalg.norm(twin[truth.left][listed] - truth.twins(deformed)[listed], axis=1) / spacing
    assert np.median(error) < 0.25 and np.percentile(error, 95) < 1.0
    # the twin is a point of the input surface, and placed on another embedding by the same weights
    np.testing.assert_allclose(pairs.twins_on(deformed), pairs.twin, atol=1e-12)
    assert np.all((pairs.confidence >= 0) & (pairs.confidence <= 1))
    assert np.all(confidence[np.isnan(twin).any(axis=1)] == 0)
    report = pairs.report
    assert report.confident_share > 0.9 and 0 < report.confident_share <= report.coverage <= 1


def test_symmetrize_reports_the_same_map(bent_remeshed_cow):
    truth, deformed, pairs = bent_remeshed_cow
    from filter_symblend import symmetrize
    result = symmetrize(deformed, faces=truth.faces, pairs="auto", mode="affine")
    np.testing.assert_array_equal(result.mirror_pairs.vertex, pairs.vertex)
    np.testing.assert_allclose(result.mirror_pairs.twin, pairs.twin)
    assert result.report.auto_pairs.mirror_map == pairs.report


def test_confidence_finds_the_part_a_map_gets_wrong(remeshed_cow):
    """The true reflection of the (undeformed, remeshed) cow, except that on one end of the body the map
    sends each point ``shift`` edges along the body (a map that tears there, as a wrong limb does): no twin
    there is confident, while the twins away from the tear are. The torn twins are listed all the same (the
    map does not come back, which their confidence says): the user sees what the map says there."""
    truth = remeshed_cow
    surface = build_surface(truth.points, truth.faces)
    offset = 0.5 * (truth.points[:, 0].max() + truth.points[:, 0].min())
    exact = plane_map(surface, [1.0, 0.0, 0.0], offset)
    end = truth.points[:, 2].max() - 0.2 * np.ptp(truth.points[:, 2])
    n = len(truth.points)
    for shift in (1.5, 3.0):
        def torn(x, shift=shift):
            predicted = exact.predict(x)
            predicted[x[:, 2] > end] += [0.0, 0.0, -shift * surface.spacing]
            return predicted

        pairs = mirror_pairs(MirrorMap("torn", surface, torn, exact.normal, exact.carry), surface,
                             np.zeros(n, dtype=bool), DEFAULT)
        confidence = pairs.per_vertex()[1]
        in_tear = truth.points[:, 2] > end + 3 * surface.spacing
        away = surface.usable & (truth.points[:, 2] < end - 5 * surface.spacing)
        print(f"shift {shift} edges: confident in the tear {np.mean(confidence[in_tear] >= CONFIDENT):.3f}, "
              f"away {np.mean(confidence[away] >= CONFIDENT):.3f}")
        assert np.mean(confidence[in_tear] >= CONFIDENT) < 0.1
        assert np.mean(confidence[away] >= CONFIDENT) > 0.9
        # every vertex of the tear has a twin: the surface's point nearest the prediction, supported where it lands
        # on the surface facing the mirrored way (72 % and 52 % of the tear; the rest is shifted off the cow's
        # rounded end, and has confidence 0)
        twin = pairs.per_vertex()[0]
        assert np.isfinite(twin[in_tear]).all()
        nearest = surface.nearest_points(torn(truth.points[in_tear]))[0]
        np.testing.assert_allclose(twin[in_tear], nearest, atol=1e-9 * surface.diagonal)
        assert 0.4 < np.mean(confidence[in_tear] > 0) < 0.8
        assert pairs.report.coverage < 1.0


def test_a_twin_the_map_does_not_support_is_listed_with_confidence_nil(remeshed_cow):
    """The true reflection of the cow, its carried normals turned over on the head (as on a thin finger, where
    a local map's normals flip): the twins there fail the facing test, so the map does not support them; they
    are listed all the same, exact (the ground truth's), with confidence 0; elsewhere they are confident. The
    report's coverage counts the supported twins only."""
    truth = remeshed_cow
    surface = build_surface(truth.points, truth.faces)
    offset = 0.5 * (truth.points[:, 0].max() + truth.points[:, 0].min())
    exact = plane_map(surface, [1.0, 0.0, 0.0], offset)
    start = truth.points[:, 2].max() - 0.2 * np.ptp(truth.points[:, 2])

    def turned(normals, positions):
        carried = exact.carry(normals, positions)
        return np.where((positions[:, 2] > start)[:, None], -carried, carried)

    pairs = mirror_pairs(MirrorMap("turned", surface, exact.predict, exact.normal, turned), surface,
                         np.zeros(len(truth.points), dtype=bool), DEFAULT)
    twin, confidence = pairs.per_vertex()
    left = truth.left[surface.usable[truth.left]]
    true_twin = truth.twins(truth.points)[surface.usable[truth.left]]
    on_head = truth.points[left, 2] > start + 2 * surface.spacing
    assert on_head.sum() > 30 and np.all(confidence[left[on_head]] == 0)
    error = np.linalg.norm(twin[left] - true_twin, axis=1) / surface.spacing
    assert np.median(error[on_head]) < 0.25 and np.percentile(error[on_head], 95) < 1.0
    away = truth.points[left, 2] < start - 5 * surface.spacing
    assert np.mean(confidence[left[away]] >= CONFIDENT) > 0.9
    assert pairs.report.coverage < 0.9 < np.mean(np.isfinite(twin[surface.usable]).all(axis=1))


def test_a_second_map_gives_the_twins_where_its_evidence_is_stronger(remeshed_cow):
    """The torn map above (3 edges off on one end of the body) with the true reflection as the second map (the
    intrinsic mirror's role): on a posed body each vertex takes the twin of the map with the higher confidence,
    each map's twins and confidences computed alone; in the tear that is the true reflection's, so the tear is
    confident again, and the report names the second map with its share. Otherwise the chosen map's confident
    twins stand, and the second map gives the others where it is more confident."""
    truth = remeshed_cow
    surface = build_surface(truth.points, truth.faces)
    offset = 0.5 * (truth.points[:, 0].max() + truth.points[:, 0].min())
    exact = plane_map(surface, [1.0, 0.0, 0.0], offset, name="true reflection")
    end = truth.points[:, 2].max() - 0.2 * np.ptp(truth.points[:, 2])

    def torn(x):
        predicted = exact.predict(x)
        predicted[x[:, 2] > end] += [0.0, 0.0, -3.0 * surface.spacing]
        return predicted

    tearing = MirrorMap("torn", surface, torn, exact.normal, exact.carry)
    none = np.zeros(len(truth.points), dtype=bool)
    (torn_twin, torn_confidence), (true_twin, true_confidence) = (
        mirror_pairs(mirror, surface, none, DEFAULT).per_vertex() for mirror in (tearing, exact))
    in_tear = truth.points[:, 2] > end + 3 * surface.spacing
    stronger = true_confidence > torn_confidence
    for posed, second in ((True, stronger), (False, stronger & (torn_confidence < CONFIDENT))):
        merged = mirror_pairs(tearing, surface, none, DEFAULT, second=exact, posed=posed)
        twin, confidence = merged.per_vertex()
        np.testing.assert_allclose(confidence, np.where(second, true_confidence, torn_confidence))
        np.testing.assert_allclose(twin[second], true_twin[second])
        np.testing.assert_allclose(twin[~second & (torn_confidence > 0)], torn_twin[~second & (torn_confidence > 0)])
        assert np.mean(second[in_tear]) > 0.9 and np.mean(confidence[in_tear] >= CONFIDENT) > 0.9
        assert re.fullmatch(r"torn; the true reflection for \d+% of the vertices", merged.report.map)
    assert np.count_nonzero(stronger & (torn_confidence >= CONFIDENT)) > 0  # where the two rules differ
    alone = mirror_pairs(tearing, surface, none, DEFAULT, second=tearing)  # the same map twice: itself
    assert alone.report.map == "torn"
    np.testing.assert_array_equal(alone.per_vertex()[1], torn_confidence)


def test_a_vertex_map_gives_its_exact_twins_where_its_evidence_is_stronger_and_not_where_it_is_scrambled():
    """The bumpy blob (exact vertex twins across x = 0): the chosen map torn on one end (3 edges off), and as the
    third opinion (the intrinsic mirror's own vertex map) the exact vertex twins, scrambled on another end. In
    the tear each vertex takes its exact twin, confident (round trip and neighbours exact); where the vertex map
    is scrambled its round trip fails, and the chosen map's twins stand."""
    points, faces = symmetric_blob(4)
    surface = build_surface(points, faces)
    exact = plane_map(surface, [1.0, 0.0, 0.0], 0.0, name="true reflection")
    top, bottom = points[:, 2].max() - 0.3 * np.ptp(points[:, 2]), points[:, 2].min() + 0.3 * np.ptp(points[:, 2])

    def torn(x):
        predicted = exact.predict(x)
        predicted[x[:, 2] > top] += [0.0, 0.0, -3.0 * surface.spacing]
        return predicted

    tearing = MirrorMap("torn", surface, torn, exact.normal, exact.carry)
    true = twins(points)
    scrambled = true.copy()
    low = np.flatnonzero(points[:, 2] < bottom)
    scrambled[low] = np.random.default_rng(4).permutation(low)
    none = np.zeros(len(points), dtype=bool)
    merged = mirror_pairs(tearing, surface, none, DEFAULT, vertex_map=scrambled)
    torn_twin, torn_confidence = mirror_pairs(tearing, surface, none, DEFAULT).per_vertex()
    twin, confidence = merged.per_vertex()
    in_tear = points[:, 2] > top + 3 * surface.spacing
    assert np.mean(np.all(twin[in_tear] == points[true[in_tear]], axis=1)) > 0.95
    assert np.mean(confidence[in_tear] >= CONFIDENT) > 0.95 and np.mean(torn_confidence[in_tear] >= CONFIDENT) < 0.1
    in_scramble = points[:, 2] < bottom - 3 * surface.spacing
    kept = np.all(twin[in_scramble] == torn_twin[in_scramble], axis=1)
    assert np.mean(kept) > 0.95 and np.mean(confidence[in_scramble] >= CONFIDENT) > 0.9
    assert re.fullmatch(r"torn; the intrinsic vertex map for \d+% of the vertices", merged.report.map)


def test_find_mirror_pairs_refuses_landmark_pairs_alone():
    points, faces = synthetic.icosphere(2)
    with pytest.raises(ParameterError, match="pairs='landmarks' has no mirror map to return"):
        find_mirror_pairs(points, faces, pairs="landmarks")


def test_an_automatic_run_in_a_meshset_carries_the_map_on_its_output(bent_remeshed_cow):
    """The output layer holds each vertex's twin on the output (the true material twin, moved by the warp) and
    its confidence, as custom attributes a script can colour by, select with or save; the input has none."""
    import pymeshlab
    from filter_symblend import CONFIDENCE_ATTRIBUTE, TWIN_ATTRIBUTE
    from filter_symblend.meshlab.attributes import custom_attribute_names
    truth, deformed, pairs = bent_remeshed_cow
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=deformed, face_matrix=truth.faces))
    report = ms.generate_symmetrized_mesh(pairs="auto", mode="affine", checks="none")
    output = ms.current_mesh()
    assert TWIN_ATTRIBUTE in custom_attribute_names(ms)["vp"]
    twin = output.vertex_custom_point_attribute_matrix(TWIN_ATTRIBUTE)
    confidence = output.vertex_custom_scalar_attribute_array(CONFIDENCE_ATTRIBUTE)
    np.testing.assert_allclose(confidence[pairs.vertex], pairs.confidence)
    listed = np.isfinite(twin[truth.left]).all(axis=1)
    moved = output.vertex_matrix()
    spacing = np.median(np.linalg.norm(moved[truth.faces[:, 0]] - moved[truth.faces[:, 1]], axis=1))
    error = np.linalg.norm(twin[truth.left][listed] - truth.twins(moved)[listed], axis=1) / spacing
    assert listed.mean() > 0.9 and np.median(error) < 0.25
    assert report["auto_pairs"]["mirror_map"]["confident_share"] == pytest.approx(pairs.report.confident_share)
    ms.set_current_mesh(report["input_mesh_id"])
    assert custom_attribute_names(ms) == {"vs": [], "vp": [], "fs": [], "fp": []}


@pytest.fixture(scope="module")
def bent_blob_file(tmp_path_factory):
    """An exactly symmetric bumpy sphere (every vertex has an exact twin), bent, as an OBJ file."""
    import pymeshlab
    points, faces = symmetric_blob(4)
    deformed = synthetic.bend(points, 0.5)
    path = tmp_path_factory.mktemp("blob") / "blob_bent.obj"
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=deformed, face_matrix=faces))
    ms.save_current_mesh(str(path))
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    return path, ms.current_mesh().vertex_matrix(), faces, twins(points)


@pytest.mark.parametrize("suffix", [".pp", ".fcsv", ".mrk.json", ".csv"])
def test_pairs_written_as_landmarks_are_true_twins_and_read_back_unedited(bent_blob_file, tmp_path, suffix, capsys):
    """`symblend pairs` writes --count confident pairs, each a vertex and its true twin, named so that
    `symblend symmetrize -l` pairs them by name; the mesh made from them is more symmetric than the input."""
    from scipy.spatial import cKDTree
    from filter_symblend.commands.main import main
    from filter_symblend.landmarks.formats import read_landmarks
    path, points, faces, true_twin = bent_blob_file
    output = tmp_path / f"pairs{suffix}"
    assert main(["pairs", str(path), "-o", str(output), "--count", "12", "--mode", "articulated"]) == 0
    assert f"{output}: 12 automatic pairs" in capsys.readouterr().out
    landmarks = read_landmarks(output).landmarks
    assert [lm.name for lm in landmarks[:4]] == ["L_auto_1", "R_auto_1", "L_auto_2", "R_auto_2"]
    assert len(landmarks) == 24
    positions = np.array([lm.position for lm in landmarks])
    distance, vertex = cKDTree(points).query(positions)
    assert distance.max() < 1e-5  # each side is a vertex: the twins of a mirrored tessellation are vertices
    np.testing.assert_array_equal(vertex[1::2], true_twin[vertex[0::2]])
    sides = positions[0::2] - positions[1::2]
    assert np.all(np.linalg.norm(sides, axis=1) > 0.02 * np.linalg.norm(np.ptp(points, axis=0)))
    symmetrized = tmp_path / "blob_sym.ply"
    assert main(["symmetrize", str(path), "-l", str(output), "-o", str(symmetrized), "--mode", "articulated",
                 "--report", str(tmp_path / "report.json")]) == 0
    import json
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["pair_count"] == 12 and report["landmarks"]["pairing"] == "names"
    before, after = report["mirror_asymmetry_before"]["p90"], report["mirror_asymmetry_after"]["p90"]
    assert after < 0.5 * before


def test_a_corrected_pairs_file_gives_the_corrected_result(bent_blob_file, tmp_path):
    """A pair deleted (PickPoints' unchecked point: active="0") and another moved onto a wrong vertex: the
    symmetrization reads the file as edited (one pair fewer; the moved one where it was put)."""
    import json
    from filter_symblend.commands.main import main
    path, points, faces, true_twin = bent_blob_file
    pairs = tmp_path / "pairs.pp"
    assert main(["pairs", str(path), "-o", str(pairs), "--count", "10"]) == 0
    text = pairs.read_text()
    text = text.replace('name="L_auto_3" active="1"', 'name="L_auto_3" active="0"')
    moved = re.sub(r'name="R_auto_5" active="1" x="[^"]*" y="[^"]*" z="[^"]*"',
                   'name="R_auto_5" active="1" x="{}" y="{}" z="{}"'.format(*points[7]), text)
    assert moved != text
    pairs.write_text(moved)
    report = tmp_path / "report.json"
    assert main(["symmetrize", str(path), "-l", str(pairs), "-o", str(tmp_path / "out.ply"),
                 "--report", str(report)]) == 0
    data = json.loads(report.read_text())
    assert data["pair_count"] == 9 and data["landmarks"]["left_out_unplaced"] == ["L_auto_3/R_auto_3"]
    assert ["R_auto_5", 7] in data["landmarks"]["vertices"]


@pytest.mark.parametrize(("arguments", "message"), [
    (["-o", "{tmp}/pairs.tps"], r"pairs.tps: write the pairs as .pp, .fcsv, .mrk.json, .csv"),
    (["-o", "{tmp}/pairs.pp", "--count", "0"], r"--count 0: give at least 1 pair to write"),
    (["-o", "{tmp}/pairs.pp", "--pairs", "landmarks"], r"pairs='landmarks' has no mirror map to return"),
])
def test_pairs_command_errors(bent_blob_file, tmp_path, capsys, arguments, message):
    from filter_symblend.commands.main import main
    path = bent_blob_file[0]
    assert main(["pairs", str(path), *[a.format(tmp=tmp_path) for a in arguments]]) == 1
    err = capsys.readouterr().err
    assert re.search(message, err), err
    assert not (tmp_path / "pairs.pp").exists() and not (tmp_path / "pairs.tps").exists()


def test_pairs_command_never_overwrites_a_file(bent_blob_file, tmp_path, capsys):
    from filter_symblend.commands.main import main
    existing = tmp_path / "mine.pp"
    existing.write_text("keep me")
    assert main(["pairs", str(bent_blob_file[0]), "-o", str(existing)]) == 1
    assert existing.read_text() == "keep me"
    assert "mine.pp: exists (pairs you corrected, perhaps); choose another file, or add --overwrite" in \
        capsys.readouterr().err


def _summary(p90: float) -> dict:
    return {"p90": p90, "p90_relative": p90 / 100, "p99": 2 * p90, "p99_relative": p90 / 50, "max": 3 * p90}


@pytest.mark.parametrize(("landmark_pairs", "automatic", "fix"), [
    (0, True, "the automatic pairs mirror the wrong parts here: write them with `symblend pairs MESH -o pairs.pp`, "
              "check and correct them in PickPoints (or place landmark pairs), then symmetrize with -l pairs.pp."),
    (3, False, "with 3 landmark pairs, add dense pairs from the surface: --pairs landmarks+auto"),
    (20, True, "check the landmark pairs (a swapped or misplaced pair?) and the mode."),
])
def test_a_worse_result_names_the_fix_of_the_run_it_was(landmark_pairs, automatic, fix):
    """Advice about landmark pairs only where there are landmark pairs."""
    from filter_symblend.measures.verdict import result_warnings
    message, = result_warnings(_summary(1.0), _summary(2.0), landmark_pairs=landmark_pairs, automatic=automatic)
    assert message.startswith("the output is more asymmetric than the input: 90th percentile 1 % -> 2 %")
    assert fix in message


def test_the_twins_survive_a_ply_file(bent_blob_file, tmp_path):
    """`symblend symmetrize --pairs auto -o out.ply` writes the twins (a point attribute, a list of 3 doubles
    in the PLY) and the confidence; loading the file re-attaches both, unchanged."""
    import pymeshlab
    from filter_symblend import CONFIDENCE_ATTRIBUTE, TWIN_ATTRIBUTE
    from filter_symblend.commands.main import main
    from filter_symblend.meshlab.ply_attributes import load_mesh_with_attributes
    path, points, faces, true_twin = bent_blob_file
    output = tmp_path / "out.ply"
    assert main(["symmetrize", str(path), "--pairs", "auto", "-o", str(output)]) == 0
    ms = pymeshlab.MeshSet()
    assert {TWIN_ATTRIBUTE, CONFIDENCE_ATTRIBUTE} <= set(load_mesh_with_attributes(ms, output))
    mesh = ms.current_mesh()
    twin = mesh.vertex_custom_point_attribute_matrix(TWIN_ATTRIBUTE)
    moved = mesh.vertex_matrix()
    listed = np.isfinite(twin).all(axis=1)
    assert listed.mean() > 0.95
    # each twin is the true twin vertex, on the output (float32 coordinates in the PLY)
    np.testing.assert_allclose(twin[listed], moved[true_twin[listed]], atol=1e-6)
    assert np.all(mesh.vertex_custom_scalar_attribute_array(CONFIDENCE_ATTRIBUTE)[listed] > 0)


def test_a_map_wrong_on_much_of_the_surface_warns_with_the_share_and_the_fix(remeshed_cow):
    """Torn over the half of the body: the confident share falls below DOUBTFUL_SHARE and the warning names
    it, the map, and the round trip through an editable pairs file; a sound map does not warn."""
    from filter_symblend.auto.confidence import doubtful_map_warning
    truth = remeshed_cow
    surface = build_surface(truth.points, truth.faces)
    exact = plane_map(surface, [1.0, 0.0, 0.0], 0.5 * (truth.points[:, 0].max() + truth.points[:, 0].min()))
    half = np.median(truth.points[:, 2])

    def torn(x):
        predicted = exact.predict(x)
        predicted[x[:, 2] > half] += [0.0, 0.0, -3.0 * surface.spacing]
        return predicted

    none = np.zeros(len(truth.points), dtype=bool)
    assert doubtful_map_warning(mirror_pairs(exact, surface, none, DEFAULT).report) is None
    report = mirror_pairs(MirrorMap("torn", surface, torn, exact.normal, exact.carry), surface, none, DEFAULT).report
    message = doubtful_map_warning(report)
    assert message == (
        f"only {report.confident_share:.0%} of the surface has a confident mirror twin (map: torn); the automatic "
        "pairs may mirror the wrong parts. Write them with `symblend pairs MESH -o pairs.pp` (find_mirror_pairs in "
        "Python), check and correct them in MeshLab's PickPoints, then symmetrize with -l pairs.pp; or place "
        "landmark pairs where the per-vertex symblend_pair_confidence is low.")
    assert report.confident_share < 0.6


@pytest.mark.corpus
def test_the_map_of_a_tosca_man_is_the_published_self_symmetry(bcicp):
    """On public ground truth (the BCICP dataset, read in place; skipped without it): TOSCA's david0, a man at
    rest, remeshed to 5,000 vertices. Its twins are the published mirror twins, nearly all of them confident."""
    from benchmarks.mirror_maps import surface_area, twin_errors
    points, faces, a, b = bcicp.shape("TOSCA", "david0")
    pairs = find_mirror_pairs(points, faces, mode="articulated")
    twin, confidence = pairs.per_vertex()
    errors = twin_errors(twin, points, a, b, np.sqrt(surface_area(points, faces)))
    assert np.mean(errors <= 0.05) > 0.98
    assert pairs.report.confident_share > 0.95


def test_the_benchmarks_landmark_run_takes_distinct_true_twin_pairs_apart_and_times_them(cow, monkeypatch):
    # the yardstick of the automatic pairs' time (issue 47): pairs from given twins, confident ones first
    import sys
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "scripts"))
    from benchmarks import mirror_maps
    taken = {}
    monkeypatch.setattr(mirror_maps, "symmetrize", lambda points, left, right, **options: taken.update(
        left=left, right=right, options=options))
    confidence = np.where(np.arange(len(cow.points)) % 2 == 0, 1.0, 0.0)
    count, seconds = mirror_maps.landmark_seconds(cow.points, cow.points[cow.partner], confidence, "standard", 300)
    left, right = taken["left"], taken["right"]
    assert count == len(left) == 300 and seconds >= 0 and taken["options"]["mode"] == "standard"
    np.testing.assert_array_equal(cow.points[cow.partner[left]], cow.points[right])  # the twins (or their copies)
    assert len(np.unique(cow.points[np.concatenate([left, right])], axis=0)) == 600
    assert (np.linalg.norm(cow.points[left] - cow.points[right], axis=1) > 0.02 * cow.diagonal).all()
    assert (confidence[left] == 1.0).all()  # enough confident twins: only those


def test_the_corpus_benchmarks_twin_scores_count_true_twins_and_confident_wrong_ones(remeshed_cow):
    # the corpus table's twin columns (issue 46): the true twins score (1, 0); moved 3 % of the diagonal on a
    # quarter of the vertices, half of them confident, they score about (0.75, 0.125)
    import sys
    from types import SimpleNamespace
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "scripts"))
    from benchmarks.corpus import twin_scores
    truth = remeshed_cow
    twin = np.full((len(truth.points), 3), np.nan)
    twin[truth.left] = truth.twins(truth.points)
    confidence = np.ones(len(truth.points))

    def result(twin, confidence):
        return SimpleNamespace(mirror_pairs=SimpleNamespace(per_vertex=lambda: (twin, confidence)))

    assert twin_scores(result(twin, confidence), truth, truth.points) == (1.0, 0.0)
    quarter = truth.left[: len(truth.left) // 4 * 4][::4]
    diagonal = np.linalg.norm(np.ptp(truth.points, axis=0))
    moved = twin.copy()
    moved[quarter] += [0.03 * diagonal, 0.0, 0.0]
    confidence[quarter[1::2]] = 0.0
    within, wrong = twin_scores(result(moved, confidence), truth, truth.points)
    assert within == pytest.approx(1 - len(quarter) / len(truth.left))
    assert wrong == pytest.approx(len(quarter[::2]) / len(truth.left))
