"""Filter scripts as each MeshLab version wrote them, and the table of MeshLab's renamed and removed filters."""

import json

import numpy as np
import pymeshlab
import pytest

from filter_symblend import DISPLAY_NAME, PARAMETERS, ScriptError, apply_filter_script
from filter_symblend.meshlab import filter_names
from filter_symblend.testing import synthetic
from conftest import meshset_with_pairs

TABLE = json.loads(filter_names.HISTORY_FILE.read_text())


def write_script(tmp_path, body, name):
    path = tmp_path / name
    path.write_text(f"<!DOCTYPE FilterScript>\n<FilterScript>\n{body}\n</FilterScript>\n")
    return path


def sphere():
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=3)
    ms.compute_matrix_from_translation(axisx=0.3, axisy=-0.2)  # off the origin: centring moves it
    return ms


def meshes(ms):
    return [(m.vertex_matrix(), m.face_matrix()) for m in ms]


# ---- the table, entry by entry --------------------------------------------------------------------

@pytest.mark.parametrize("entry", TABLE["renamed"], ids=lambda e: e["old"])
def test_every_renamed_filter_runs_as_the_filter_it_is_now(entry):
    now = filter_names.pymeshlab_filter_name(entry["now"])
    assert now is not None, f"{entry['now']!r} is not a filter of this pymeshlab"
    assert filter_names.pymeshlab_filter_name(filter_names.renamed(entry["old"].upper()).now) == now
    parameters = pymeshlab.MeshSet()
    parameters.create_cube()
    known = {filter_names.python_name(p) for p in parameters.filter_parameter_values(now)}
    targets = [change.get("name", old) for old, change in entry.get("parameters", {}).items()]
    assert {filter_names.python_name(t) for t in targets + list(entry.get("add", {}))} <= known


# The old form of each entry that translates parameters, and the call of today's filter it must equal.
TRANSLATED = [
    ('<filter name="Transform: Move, Translate, Center"><Param name="axisX" value="0" type="RichDynamicFloat"/>'
     '<Param name="axisY" value="0" type="RichDynamicFloat"/><Param name="axisZ" value="0" type="RichDynamicFloat"/>'
     '<Param name="centerFlag" value="true" type="RichBool"/><Param name="Freeze" value="true" type="RichBool"/>'
     '<Param name="ToAll" value="false" type="RichBool"/></filter>',
     "compute_matrix_from_translation", {"traslmethod": "Center on Layer BBox"}),
    ('<filter name="Transform: Move, Translate, Center"><Param name="axisX" value="0.5" type="RichDynamicFloat"/>'
     '<Param name="centerFlag" value="false" type="RichBool"/><Param name="ToAll" value="true" type="RichBool"/></filter>',
     "compute_matrix_from_translation", {"traslmethod": "XYZ translation", "axisx": 0.5, "alllayers": True}),
    ('<filter name="Transform: Scale"><Param name="axisX" value="2" type="RichFloat"/>'
     '<Param name="ToAll" value="false" type="RichBool"/></filter>',
     "compute_matrix_from_scaling_or_normalization", {"axisx": 2.0}),
    ('<filter name="Transform: Rotate"><Param name="rotAxis" value="2" type="RichEnum"/>'
     '<Param name="angle" value="30" type="RichDynamicFloat"/><Param name="ToAll" value="false" type="RichBool"/></filter>',
     "compute_matrix_from_rotation", {"rotaxis": "Z axis", "angle": 30.0}),
    ('<filter name="Remove T-Vertices by Edge Flip"><Param name="Threshold" value="40" type="RichFloat"/></filter>',
     "meshing_remove_t_vertices", {"method": "Edge Flip"}),
    ('<filter name="Remove T-Vertices by Edge Collapse"/>', "meshing_remove_t_vertices", {"method": "Edge Collapse"}),
    ('<filter name="Remove Faces from Non Manifold Edges"/>', "meshing_repair_non_manifold_edges", {"method": "Remove Faces"}),
    ('<filter name="Repair non Manifold Edges by splitting vertices"/>', "meshing_repair_non_manifold_edges",
     {"method": "Split Vertices"}),
]


@pytest.mark.parametrize("old, now, values", TRANSLATED, ids=[t[0][14:50] for t in TRANSLATED])
def test_an_old_filter_with_translated_parameters_does_what_todays_filter_does(tmp_path, old, now, values):
    ms, expected = sphere(), sphere()
    ms.create_sphere(subdiv=1)  # a second layer, so that "all layers" means something
    expected.create_sphere(subdiv=1)
    ms.set_current_mesh(0)
    expected.set_current_mesh(0)
    steps = apply_filter_script(ms, write_script(tmp_path, old, "old.mlx"))
    expected.apply_filter(now, **values)
    for (points, faces), (want_points, want_faces) in zip(meshes(ms), meshes(expected)):
        np.testing.assert_array_equal(points, want_points)
        np.testing.assert_array_equal(faces, want_faces)
    assert "runs as today's" in steps[0]["translated"]


@pytest.mark.parametrize("entry", TABLE["removed"], ids=lambda e: e["name"])
def test_every_removed_filter_is_refused_with_the_version_that_dropped_it(tmp_path, entry):
    assert filter_names.pymeshlab_filter_name(entry["name"]) is None
    path = write_script(tmp_path, f'<filter name="{entry["name"]}"/>', "removed.mlx")
    with pytest.raises(ScriptError) as error:
        apply_filter_script(sphere(), path)
    assert f"filter 1 ('{entry['name']}'): MeshLab removed this filter in {entry['dropped_in']}." in str(error.value)
    assert (entry["instead"] or "It has no successor; drop the step.") in str(error.value)


OLD_POISSON = ('<filter name="Surface Reconstruction: Poisson">'
               '<Param name="OctDepth" value="6" type="RichInt"/><Param name="SolverDivide" value="6" type="RichInt"/>'
               '<Param name="SamplesPerNode" value="1" type="RichFloat"/><Param name="Offset" value="1" type="RichFloat"/>'
               '</filter>')  # as MeshLab 1.3 saved it


def test_a_removed_filter_with_a_replacement_is_refused_by_default_and_names_the_way_to_accept_it(tmp_path):
    ms = sphere()
    before = meshes(ms)
    with pytest.raises(ScriptError) as error:
        apply_filter_script(ms, write_script(tmp_path, OLD_POISSON, "poisson.mlx"))
    assert ("MeshLab removed this filter in 2016.12. Instead: Surface Reconstruction: Screened Poisson with "
            "Interpolation Weight 0 comes closest (not identical). To run the replacement, accept it: symblend mlx "
            "--accept-replacements (Python: apply_filter_script(..., accept_replacements=True)).") in str(error.value)
    assert all((a == b).all() for pair in zip(before, meshes(ms)) for a, b in zip(*pair))


def test_the_old_poisson_accepted_runs_as_screened_poisson_with_its_parameters_mapped(tmp_path):
    ms, expected = sphere(), sphere()
    steps = apply_filter_script(ms, write_script(tmp_path, OLD_POISSON, "poisson.mlx"), accept_replacements=True)
    expected.apply_filter("generate_surface_reconstruction_screened_poisson", depth=6, samplespernode=1.0,
                          pointweight=0.0)
    assert ms.mesh_number() == expected.mesh_number() == 2
    got, want = (np.unique(m.current_mesh().vertex_matrix(), axis=0) for m in (ms, expected))  # threads reorder
    np.testing.assert_allclose(got, want)
    assert ms.current_mesh().face_number() == expected.current_mesh().face_number()
    assert steps[0]["translated"] == (
        "'Surface Reconstruction: Poisson' (removed in MeshLab 2016.12) replaced, as accepted, by 'Surface "
        "Reconstruction: Screened Poisson'; parameters translated: OctDepth -> depth, SamplesPerNode -> samplesPerNode; "
        "added: pointWeight=0; not carried over: SolverDivide=6 (the screened solver has no block Gauss-Seidel "
        "divide), Offset=1 (the screened solver has no iso-surface offset)")


@pytest.mark.parametrize("entry", [e for e in TABLE["removed"] if "replacement" in e], ids=lambda e: e["name"])
def test_every_recorded_replacement_runs(tmp_path, entry):
    ms = sphere()
    before = meshes(ms)
    steps = apply_filter_script(ms, write_script(tmp_path, f'<filter name="{entry["name"]}"/>', "old.mlx"),
                                accept_replacements=True)
    assert f"'{entry['name']}' (removed in MeshLab {entry['dropped_in']})" in steps[0]["translated"]
    if entry["replacement"]["now"] is None:  # the step is dropped: the mesh as it was
        assert "dropped, as accepted" in steps[0]["translated"] and steps[0]["output"] is None
        assert all((a == b).all() for pair in zip(before, meshes(ms)) for a, b in zip(*pair))
    else:
        assert filter_names.pymeshlab_filter_name(entry["replacement"]["now"]) is not None


def test_accepting_replacements_still_refuses_a_removed_filter_without_one(tmp_path):
    path = write_script(tmp_path, '<filter name="Select Folded Faces"/>', "old.mlx")
    with pytest.raises(ScriptError, match=r"MeshLab removed this filter in 2021.10. It has no successor; drop the "
                                          r"step.$"):
        apply_filter_script(sphere(), path, accept_replacements=True)


def test_every_recorded_meshlab_name_resolves_to_its_filter():
    assert len(TABLE["display_names"]) > 150
    wrong = {f: shown for f, shown in TABLE["display_names"].items() if filter_names.pymeshlab_filter_name(shown) != f}
    assert not wrong


@pytest.mark.parametrize("written, suggested", [
    ("Close Hole", "'Close Holes' (pymeshlab: meshing_close_holes)"),
    ("Remove Duplicated Vertexes", "'Remove Duplicate Vertices' (pymeshlab: meshing_remove_duplicate_vertices)"),
    ("Quadric Edge Collapse Decimatio",
     "'Simplification: Quadric Edge Collapse Decimation' (pymeshlab: meshing_decimation_quadric_edge_collapse)"),
])
def test_an_unknown_filter_is_refused_with_the_closest_in_meshlabs_spelling(tmp_path, written, suggested):
    with pytest.raises(ScriptError) as error:
        apply_filter_script(sphere(), write_script(tmp_path, f'<filter name="{written}"/>', "typo.mlx"))
    assert str(error.value).startswith(f"{tmp_path / 'typo.mlx'}, filter 1 ('{written}'): no version of MeshLab "
                                       f"had a filter of this name. The closest MeshLab filter is {suggested}")


def test_todays_form_of_a_filter_whose_parameters_were_renamed_runs_untranslated(tmp_path):
    today = write_script(tmp_path, '<filter name="Transform: Rotate"><Param name="angle" value="30" '
                                   'type="RichDynamicFloat"/><Param name="allLayers" value="false" type="RichBool"/>'
                                   '</filter>', "today.mlx")
    old = write_script(tmp_path, '<filter name="Transform: Rotate"><Param name="angle" value="30" '
                                 'type="RichDynamicFloat"/><Param name="ToAll" value="false" type="RichBool"/>'
                                 '</filter>', "old.mlx")
    assert "translated" not in apply_filter_script(sphere(), today)[0]
    assert apply_filter_script(sphere(), old)[0]["translated"] == (
        "'Transform: Rotate' (MeshLab 1.3.4BETA) runs as today's 'Transform: Rotate', parameters translated: "
        "ToAll -> allLayers")


def test_xml_filter_errors_name_the_parameter(tmp_path):
    no_value = write_script(tmp_path, '<xmlfilter name="Close Holes"><xmlparam name="MaxHoleSize"/></xmlfilter>', "a.mlx")
    with pytest.raises(ScriptError, match=r"filter 1 \('Close Holes'\): every <xmlparam> needs a name and a value"):
        apply_filter_script(sphere(), no_value)
    point = write_script(tmp_path, '<xmlfilter name="Transform: Translate, Center, set Origin">'
                                   '<xmlparam name="newOrigin" value="1 2 3"/></xmlfilter>', "b.mlx")
    with pytest.raises(ScriptError, match="<xmlparam> `newOrigin` has no type, and pymeshlab expects ndarray; "
                                          "write it as a <Param> with its type"):
        apply_filter_script(sphere(), point)


# ---- whole scripts, as each version wrote them ----------------------------------------------------

def _param(kind, name, value, era):
    extra = {"2016.12": ' isxmlparam="0"', "2022.02": f' description="{name}" tooltip="{name}"',
             "2023.12": f' description="{name}" tooltip="the {name}" isxmlparam="0"'}.get(era, "")
    return f'<Param{extra} type="{kind}" name="{name}" value="{value}"/>'


def era_script(era):
    """Cleaning, centring and a quality field, as MeshLab ``era`` wrote them (same effect in every era)."""
    p = lambda kind, name, value: _param(kind, name, value, era)  # noqa: E731
    if era == "1.3.4BETA":
        return "\n".join([
            '<filter name="Remove Duplicated Vertex"/>', '<filter name="Remove Unreferenced Vertex"/>',
            '<filter name="Transform: Move, Translate, Center">' + p("RichDynamicFloat", "axisX", 0)
            + p("RichDynamicFloat", "axisY", 0) + p("RichDynamicFloat", "axisZ", 0) + p("RichBool", "centerFlag", "true")
            + p("RichBool", "Freeze", "true") + p("RichBool", "ToAll", "false") + "</filter>",
            '<filter name="Remove T-Vertices by Edge Collapse">' + p("RichFloat", "Threshold", 40)
            + p("RichBool", "Repeat", "true") + "</filter>"])
    if era == "2020.05":
        return "\n".join([
            '<filter name="Remove Duplicate Vertices"/>', '<filter name="Remove Unreferenced Vertices"/>',
            '<filter name="Transform: Translate, Center, set Origin">' + p("RichEnum", "traslMethod", 2) + "</filter>",
            '<filter name="Remove T-Vertices by Edge Collapse"/>',
            '<xmlfilter name="Compute Geometric Measures"/>',
            '<xmlfilter name="Per Vertex Quality Function"><xmlparam name="q" value="x*x"/>'
            '<xmlparam name="normalize" value="false"/></xmlfilter>'])
    names = {"2016.12": ("Remove Duplicate Vertices", "Remove Unreferenced Vertices")}.get(
        era, ("Remove Duplicate Vertices", "Remove Unreferenced Vertices"))
    t_vertices = ('<filter name="Remove T-Vertices by Edge Collapse"/>' if era == "2016.12" else
                  '<filter name="Remove T-Vertices">' + p("RichEnum", "method", 0) + "</filter>")
    return "\n".join([f'<filter name="{names[0]}"/>', f'<filter name="{names[1]}"/>',
                      '<filter name="Transform: Translate, Center, set Origin">' + p("RichEnum", "traslMethod", 2)
                      + p("RichBool", "Freeze", "true") + p("RichBool", "allLayers", "false") + "</filter>",
                      t_vertices])


ERAS = ["1.3.4BETA", "2016.12", "2020.05", "2022.02", "2023.12"]


def _today(ms):
    """What every era's script does, called in today's pymeshlab."""
    ms.meshing_remove_duplicate_vertices()
    ms.meshing_remove_unreferenced_vertices()
    ms.compute_matrix_from_translation(traslmethod="Center on Layer BBox")
    ms.meshing_remove_t_vertices(method="Edge Collapse")


@pytest.fixture(scope="module")
def bent_cow(cow):
    left, right = cow.landmarks(100)
    return synthetic.bend(cow.points, 0.8), cow.faces, left, right


@pytest.mark.parametrize("era", ERAS)
def test_a_script_of_every_meshlab_era_runs_alone_and_with_our_filter_appended(tmp_path, bent_cow, era):
    points, faces, left, right = bent_cow
    ours = (f'<filter name="{DISPLAY_NAME}">' + "".join(
        _param({"enum": "RichEnum", "float": "RichFloat", "int": "RichInt", "string": "RichString"}[p.kind], p.name,
               p.choices.index(p.default) if p.kind == "enum" else p.default, era) for p in PARAMETERS) + "</filter>")
    alone = write_script(tmp_path, era_script(era), "alone.mlx")
    appended = write_script(tmp_path, era_script(era) + "\n" + ours, "appended.mlx")
    expected = meshset_with_pairs(points, faces, left, right)
    _today(expected)
    ms = meshset_with_pairs(points, faces, left, right)
    apply_filter_script(ms, alone)
    np.testing.assert_array_equal(ms.current_mesh().vertex_matrix(), expected.current_mesh().vertex_matrix())
    if era == "2020.05":
        np.testing.assert_allclose(ms.current_mesh().vertex_scalar_array(), ms.current_mesh().vertex_matrix()[:, 0] ** 2)
    expected.generate_symmetrized_mesh()
    ms = meshset_with_pairs(points, faces, left, right)
    steps = apply_filter_script(ms, appended)
    assert steps[-1]["output"]["mirror_asymmetry_after"]["rms"] < 0.1 * steps[-1]["output"]["mirror_asymmetry_before"]["rms"]
    np.testing.assert_allclose(ms.current_mesh().vertex_matrix(), expected.current_mesh().vertex_matrix(), atol=1e-12)
    assert [("translated" in step) for step in steps[:4]] == {
        "1.3.4BETA": [True] * 4, "2016.12": [False, False, False, True], "2020.05": [False, False, False, True]}.get(
        era, [False] * 4)
