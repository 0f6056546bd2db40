"""MeshLab filter scripts: validation, native equivalence, mixed scripts, atomicity, recording, presets."""

import pathlib

import numpy as np
import pymeshlab
import pytest

import filter_symblend
from filter_symblend import DISPLAY_NAME, PARAMETERS, ScriptError, apply_filter_script, save_filter_script
from filter_symblend.measures.surface_asymmetry import mirror_distances
from filter_symblend.meshlab.filter_script import read_filter_script, symblend_options
from filter_symblend.testing import synthetic
from conftest import meshset_with_pairs

PRESETS = pathlib.Path(__file__).resolve().parents[1] / "mlx_presets"
OUR_NODE = f'<filter name="{DISPLAY_NAME}">{{params}}</filter>'


def script(tmp_path, *filters, name="script.mlx"):
    path = tmp_path / name
    path.write_text("<!DOCTYPE FilterScript>\n<FilterScript>\n" + "\n".join(filters) + "\n</FilterScript>\n")
    return path


def param(kind, name, value, **extra):
    more = "".join(f' {k}="{v}"' for k, v in extra.items())
    return f'<Param type="{kind}" name="{name}" value="{value}"{more}/>'


NATIVE = [
    '<filter name="Remove Duplicate Vertices"/>',
    '<filter name="Close Holes">' + param("RichInt", "MaxHoleSize", 300) + param("RichBool", "Selected", "false")
    + param("RichBool", "RefineHole", "true") + param("RichAbsPerc", "RefineHoleEdgeLen", 0.05, min=0, max=2) + "</filter>",
    '<filter name="Taubin Smooth">' + param("RichFloat", "lambda", 0.5) + param("RichInt", "stepSmoothNum", 5)
    + param("RichBool", "Selected", "false") + "</filter>",
    '<filter name="Simplification: Quadric Edge Collapse Decimation">' + param("RichInt", "TargetFaceNum", 2500)
    + param("RichBool", "Selected", "false") + "</filter>",
]


@pytest.fixture()
def holed_cow(cow):
    """The bent cow with a hole in its left flank; landmark pairs outside the hole."""
    centre = cow.points[np.argmax(cow.points[:, 0])]
    cut = np.linalg.norm(cow.points - centre, axis=1) < 0.06 * cow.diagonal
    faces = cow.faces[~cut[cow.faces].any(axis=1)]
    used = np.unique(faces)
    remap = -np.ones(len(cow.points), dtype=int)
    remap[used] = np.arange(len(used))
    left, right = cow.landmarks(120)
    kept = (remap[left] >= 0) & (remap[right] >= 0)
    bent = synthetic.bend(cow.points, 0.8)[used]
    return meshset_with_pairs(bent, remap[faces], remap[left[kept]], remap[right[kept]])


def state(ms):
    """Everything a failed script must leave as it was."""
    return ([m.id() for m in ms], ms.current_mesh_id(),
            [(m.vertex_matrix().copy(), m.face_matrix().copy(), m.vertex_selection_array().copy()) for m in ms])


def assert_same_state(a, b):
    assert a[0] == b[0] and a[1] == b[1]
    for (va, fa, sa), (vb, fb, sb) in zip(a[2], b[2]):
        np.testing.assert_array_equal(va, vb)
        np.testing.assert_array_equal(fa, fb)
        np.testing.assert_array_equal(sa, sb)


def test_a_native_only_script_gives_what_pymeshlab_gives(tmp_path, holed_cow):
    path = script(tmp_path, *NATIVE)
    reference = pymeshlab.MeshSet()
    reference.add_mesh(holed_cow.current_mesh())
    reference.load_filter_script(str(path))
    reference.apply_filter_script()
    apply_filter_script(holed_cow, path)
    ours, theirs = holed_cow.current_mesh(), reference.current_mesh()
    assert ours.face_number() == theirs.face_number() == 2500
    np.testing.assert_array_equal(ours.vertex_matrix(), theirs.vertex_matrix())
    np.testing.assert_array_equal(ours.face_matrix(), theirs.face_matrix())


def test_a_mixed_script_runs_in_order_and_matches_the_python_calls(tmp_path, holed_cow, cow):
    ours_params = param("RichEnum", "mode", 1, enum_cardinality=3, enum_val0="standard", enum_val1="affine",
                        enum_val2="articulated") + param("RichFloat", "phi_width", 6)
    path = script(tmp_path, NATIVE[0], OUR_NODE.format(params=ours_params), NATIVE[3])
    by_hand = meshset_with_pairs(holed_cow.current_mesh().vertex_matrix(), holed_cow.current_mesh().face_matrix(),
                                 *_pairs(holed_cow))
    steps = apply_filter_script(holed_cow, path)
    assert [s["filter"] for s in steps] == ["Remove Duplicate Vertices", DISPLAY_NAME,
                                           "Simplification: Quadric Edge Collapse Decimation"]
    report = steps[1]["output"]
    assert report["mode"] == "affine" and report["phi_width"] == 6
    assert report["mirror_asymmetry_after"]["rms"] < report["mirror_asymmetry_before"]["rms"] / 5
    by_hand.meshing_remove_duplicate_vertices()
    by_hand.generate_symmetrized_mesh(mode="affine", phi_width=6)
    by_hand.meshing_decimation_quadric_edge_collapse(targetfacenum=2500, selected=False)
    np.testing.assert_array_equal(holed_cow.current_mesh().vertex_matrix(), by_hand.current_mesh().vertex_matrix())
    assert [m.id() for m in holed_cow] == [m.id() for m in by_hand]


def _pairs(ms):
    labels = ms.current_mesh().vertex_custom_scalar_attribute_array("symblend_pair")
    k = np.arange(1, int(labels.max()) + 1)
    left = np.array([np.flatnonzero(labels == i)[0] for i in k])
    right = np.array([np.flatnonzero(labels == -i)[0] for i in k])
    return left, right


def test_a_script_node_is_validated_once_when_the_script_is_read(tmp_path, holed_cow, monkeypatch):
    """Its options are checked when the script is read (so a bad node changes nothing), and not again at
    each of its runs (the rehearsal on a copy and the real one)."""
    from filter_symblend import parameters

    path = script(tmp_path, OUR_NODE.format(params=param("RichFloat", "phi_width", 6)))
    checked = []
    validate = parameters.Parameter.validate
    monkeypatch.setattr(parameters.Parameter, "validate", lambda self, value: checked.append(self.name) or
                        validate(self, value))
    steps = apply_filter_script(holed_cow, path)
    assert steps[0]["output"]["phi_width"] == 6
    assert sorted(checked) == sorted(p.name for p in PARAMETERS)  # each parameter once


@pytest.mark.parametrize("filters, message", [
    (['<filter name="Close Hole"/>'], "no version of MeshLab had a filter of this name. The closest MeshLab filter "
                                      "is 'Close Holes' (pymeshlab: meshing_close_holes)"),
    (['<filter name="Symmetrize: Closed-form Blending of Local Symmetry"/>'], f'Did you mean "{DISPLAY_NAME}"'),
    (['<filter name="Close Holes">' + param("RichInt", "MaxHolSize", 3) + "</filter>"],
     "has no parameter `MaxHolSize`. Did you mean `maxholesize`?"),
    (['<filter name="Close Holes">' + param("RichFloat", "MaxHoleSize", 3.5) + "</filter>"],
     "parameter `MaxHoleSize` is given as RichFloat but pymeshlab expects int"),
    (['<filter name="Close Holes">' + param("RichInt", "MaxHoleSize", "many") + "</filter>"],
     "parameter `MaxHoleSize` (RichInt) has an invalid value: 'many'"),
    (['<filter name="Close Holes">' + param("RichShotf", "MaxHoleSize", 1) + "</filter>"],
     "has type RichShotf, which this runner does not support"),
    ([OUR_NODE.format(params=param("RichFloat", "phi_widht", 3))], "unknown parameter `phi_widht`. Did you mean `phi_width`?"),
    ([OUR_NODE.format(params=param("RichInt", "phi_width", 3))], "parameter `phi_width` has type RichInt; it must be RichFloat"),
    ([OUR_NODE.format(params=param("RichEnum", "mode", 7))], "parameter `mode` = '7' is not valid"),
    ([OUR_NODE.format(params=param("RichFloat", "alpha", -1))], "`alpha` must be in (0, 100], got -1.0"),
    (["<notafilter/>"], 'element 2: expected <filter name="..."> (or MeshLab\'s older <xmlfilter name="...">), '
                        'got <notafilter>'),
])
def test_every_validation_error_names_the_node_and_runs_nothing(tmp_path, holed_cow, filters, message):
    path = script(tmp_path, NATIVE[0], *filters)
    before = state(holed_cow)
    with pytest.raises(ScriptError) as error:
        apply_filter_script(holed_cow, path)
    assert message in str(error.value)
    assert_same_state(before, state(holed_cow))


def test_file_errors(tmp_path, holed_cow):
    with pytest.raises(ScriptError, match="no such filter script"):
        apply_filter_script(holed_cow, tmp_path / "absent.mlx")
    (tmp_path / "bad.mlx").write_text("<FilterScript><filter name='x'></FilterScript>")
    with pytest.raises(ScriptError, match="not valid XML"):
        apply_filter_script(holed_cow, tmp_path / "bad.mlx")
    (tmp_path / "root.mlx").write_text("<Scene/>")
    with pytest.raises(ScriptError, match="the root element is <Scene>"):
        apply_filter_script(holed_cow, tmp_path / "root.mlx")
    with pytest.raises(filter_symblend.MeshSetError, match="The MeshSet is empty"):
        apply_filter_script(pymeshlab.MeshSet(), script(tmp_path, NATIVE[0]))


def test_a_failure_mid_script_leaves_the_meshset_as_it_was(tmp_path, holed_cow):
    # Our node reads an attribute the mesh lacks: it fails after two native filters ran (on the rehearsal copy).
    failing = OUR_NODE.format(params=param("RichString", "pair_attribute", "no_such_pairs"))
    holed_cow.compute_selection_by_condition_per_vertex(condselect="symblend_pair > 0")
    before = state(holed_cow)
    with pytest.raises(ScriptError, match=r"filter 3 \('Symmetrize.*has no per-vertex custom scalar attribute `no_such_pairs`"):
        apply_filter_script(holed_cow, script(tmp_path, NATIVE[0], NATIVE[1], failing))
    assert_same_state(before, state(holed_cow))


def test_a_layer_id_that_does_not_exist_is_an_error_not_a_crash(tmp_path, holed_cow):
    hausdorff = ('<filter name="Hausdorff Distance">' + param("RichMesh", "SampledMesh", 0)
                 + param("RichMesh", "TargetMesh", 7) + "</filter>")
    with pytest.raises(ScriptError, match=r"parameter `TargetMesh` refers to layer 7, which does not exist at this step \(layers: 0\)"):
        apply_filter_script(holed_cow, script(tmp_path, NATIVE[0], hausdorff))


def test_a_pipeline_built_in_python_is_saved_as_a_script_and_replays_the_same(tmp_path, holed_cow):
    replay = meshset_with_pairs(holed_cow.current_mesh().vertex_matrix(), holed_cow.current_mesh().face_matrix(),
                                *_pairs(holed_cow))
    holed_cow.meshing_close_holes(maxholesize=300, refinehole=True, selected=False)
    holed_cow.generate_symmetrized_mesh(mode="affine", missing_region="selection", alpha=0.02)
    holed_cow.apply_coord_taubin_smoothing(selected=True)
    path = tmp_path / "recorded.mlx"
    save_filter_script(holed_cow, path)
    nodes = read_filter_script(path)
    assert [n.name for n in nodes] == ["Close Holes", DISPLAY_NAME, "Taubin Smooth"]
    assert symblend_options(nodes[1], path) == {**{p.name: p.default for p in PARAMETERS},
                                                "mode": "affine", "missing_region": "selection", "alpha": 0.02}
    apply_filter_script(replay, path)
    np.testing.assert_array_equal(replay.current_mesh().vertex_matrix(), holed_cow.current_mesh().vertex_matrix())


def test_saving_after_the_recording_was_cleared_is_an_error(tmp_path, holed_cow):
    holed_cow.generate_symmetrized_mesh()
    holed_cow.clear_filter_script()
    with pytest.raises(ScriptError, match="no longer matches the calls of our filter"):
        save_filter_script(holed_cow, tmp_path / "x.mlx")


@pytest.mark.parametrize("preset", sorted(p.name for p in PRESETS.glob("*.mlx")))
def test_presets_write_our_node_from_the_parameter_declaration(preset):
    for node in read_filter_script(PRESETS / preset):
        if node.is_symblend:
            assert [p["name"] for p in node.params] == [p.name for p in PARAMETERS]
            symblend_options(node, preset)  # valid


def test_fossil_restoration_preset(holed_cow, cow):
    before_vertices = holed_cow.current_mesh().vertex_number()
    steps = apply_filter_script(holed_cow, PRESETS / "fossil_restoration.mlx")
    report = steps[3]["output"]
    assert report["mode"] == "affine" and report["filled_vertices"] > 10
    assert holed_cow.current_mesh().vertex_number() > before_vertices  # the hole was refined and filled
    after = report["mirror_asymmetry_after"]
    assert after["rms_relative"] < report["mirror_asymmetry_before"]["rms_relative"] / 5
    output = holed_cow.current_mesh().vertex_matrix()
    patch = mirror_distances(output, holed_cow.current_mesh().face_matrix(), after["plane_normal"],
                             after["plane_offset"])[before_vertices:]
    assert patch.max() < 0.01 * report["diagonal"]  # measured 0.41 %: the patch is its mirror twin's image


def test_articulated_pose_preset(cow):
    left, right = cow.landmarks(150)
    weights = synthetic.limb_weights(cow.points, **synthetic.LIMBS["cow"])
    posed = synthetic.articulate_limb(cow.points, weights, 0.5)
    ms = meshset_with_pairs(posed, cow.faces, left, right)
    report = apply_filter_script(ms, PRESETS / "articulated_pose.mlx")[0]["output"]
    assert report["mode"] == "articulated"
    assert synthetic.symmetry_error(ms.current_mesh().vertex_matrix(), cow.all_left, cow.all_right) < \
        synthetic.symmetry_error(posed, cow.all_left, cow.all_right) / 5


@pytest.mark.auto
def test_scan_cleanup_preset_needs_no_landmarks_and_simplifies_the_whole_mesh_despite_a_leftover_selection(cow):
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=synthetic.random_rigid(synthetic.bend(cow.points, 0.2), seed=6),
                               face_matrix=cow.faces))
    ms.compute_selection_by_condition_per_face(condselect="fi < 10")  # a leftover selection of 10 faces
    steps = apply_filter_script(ms, PRESETS / "scan_cleanup.mlx")
    output = steps[0]["output"]
    assert output["pair_count"] == 0 and output["auto_pairs"]["pair_count"] > 500
    assert output["mirror_asymmetry_after"]["rms"] < output["mirror_asymmetry_before"]["rms"] / 2
    assert ms.current_mesh().face_number() == len(cow.faces) // 2


def test_a_param_without_name_or_type_is_refused(tmp_path, holed_cow):
    path = script(tmp_path, '<filter name="Close Holes"><Param value="3"/></filter>')
    with pytest.raises(ScriptError, match=r"filter 1 \('Close Holes'\): every <Param> needs a name and a type"):
        apply_filter_script(holed_cow, path)


def test_a_meshlab_failure_names_the_step_and_changes_nothing(tmp_path, holed_cow):
    needs_wedge_uv = '<filter name="Convert PerWedge UV into PerVertex UV"/>'  # the cow has no UVs
    before = state(holed_cow)
    with pytest.raises(ScriptError, match=r"filter 2 \('Convert PerWedge UV into PerVertex UV'\): MeshLab failed: "
                                          r".*does not have Per"):
        apply_filter_script(holed_cow, script(tmp_path, NATIVE[0], needs_wedge_uv))
    assert_same_state(before, state(holed_cow))
