"""Landmark files: round trips for every format, real-world quirks, frames, errors."""

import json

import pytest

from filter_symblend import SymblendWarning
from filter_symblend.landmarks.curves import find_curves
from filter_symblend.landmarks.formats import (FORMATS, Landmark, LandmarkFileError, LandmarkSet, read_landmarks,
                                            write_landmarks)

SAMPLE = LandmarkSet([
    Landmark("L_orbitale", (1.25, -2.5, 3.0)),
    Landmark("R_orbitale", (-1.25, -2.5, 3.0)),
    Landmark("nasion", (0.0, 4.0, 1e-7)),
    Landmark("L_porion", (0.0, 0.0, 0.0), placed=False),
], coordinate_system="LPS")


@pytest.mark.parametrize("suffix", sorted(FORMATS))
def test_round_trip(tmp_path, suffix):
    path = tmp_path / f"points{suffix}"
    write_landmarks(path, SAMPLE)
    back = read_landmarks(path)
    # TPS names landmarks by number (pair tables by number work)
    assert back.names() == (["1", "2", "3", "4"] if suffix in (".tps", ".nts") else SAMPLE.names())
    assert [lm.placed for lm in back.landmarks] == [True, True, True, False]
    for a, b in zip(back.landmarks[:3], SAMPLE.landmarks[:3]):
        assert a.position == b.position
    if suffix in (".fcsv", ".mrk.json"):
        assert back.coordinate_system == "LPS"
    assert not list(tmp_path.glob("*partial*"))


def test_meshlab_pickpoints_with_unplaced_points(tmp_path):
    path = tmp_path / "skull_picked_points.pp"
    path.write_text("""<!DOCTYPE PickedPoints>
<PickedPoints>
 <DocumentData>
  <DateTime time="10:01:02" date="2025-01-01"/>
  <User name="anna"/>
  <DataFileName name="skull.ply"/>
  <templateName name="primate"/>
 </DocumentData>
 <point x="1.5" y="2" z="-3" active="1" name="L_zygion"/>
 <point x="0" y="0" z="0" active="0" name="R_zygion"/>
</PickedPoints>
""")
    points = read_landmarks(path)
    assert points.names() == ["L_zygion", "R_zygion"]
    assert points.landmarks[0].position == (1.5, 2.0, -3.0)
    assert [lm.placed for lm in points.landmarks] == [True, False]
    assert points.coordinate_system is None


def test_slicer5_fcsv_with_extra_columns_and_status(tmp_path):
    path = tmp_path / "points.fcsv"
    path.write_text("""# Markups fiducial file version = 5.6
# CoordinateSystem = RAS
# columns = id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID,orientationExtra,positionStatus
1,10.5,-3,2,0,0,0,1,1,1,0,"L_gonion, left",,vtkMRMLModelNode4,0,defined
2,-10.5,-3,2,0,0,0,1,1,1,0,R_gonion,,vtkMRMLModelNode4,0,undefined
""")
    points = read_landmarks(path)
    assert points.coordinate_system == "RAS"
    assert points.names() == ["L_gonion, left", "R_gonion"]
    assert [lm.placed for lm in points.landmarks] == [True, False]
    converted, note = points.in_frame("LPS")
    assert converted.landmarks[0].position == (-10.5, 3.0, 2.0)
    assert note == "coordinates converted from RAS to LPS (x and y negated)"
    assert points.in_frame("RAS")[1] == "coordinates used as stored"


@pytest.mark.parametrize("code, system", [("0", "RAS"), ("1", "LPS")])
def test_old_fcsv_numeric_coordinate_system(tmp_path, code, system):
    path = tmp_path / "old.fcsv"
    path.write_text(f"# Markups fiducial file version = 4.6\n# CoordinateSystem = {code}\n"
                    "# columns = id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID\n"
                    "vtkMRMLMarkupsFiducialNode_0,1,2,3,0,0,0,1,1,1,0,F-1,,\n")
    points = read_landmarks(path)
    assert points.coordinate_system == system and points.landmarks[0].position == (1.0, 2.0, 3.0)


def test_slicer_json_status_and_system(tmp_path):
    path = tmp_path / "points.mrk.json"
    path.write_text('{"@schema": "x", "markups": [{"type": "Fiducial", "coordinateSystem": "RAS", "controlPoints": ['
                    '{"label": "L_a", "position": [1, 2, 3], "positionStatus": "defined"},'
                    '{"label": "R_a", "position": [0, 0, 0], "positionStatus": "preview"}]}]}')
    points = read_landmarks(path)
    assert points.coordinate_system == "RAS" and [lm.placed for lm in points.landmarks] == [True, False]


def test_landmark_editor_pts_with_missing_values(tmp_path):
    path = tmp_path / "points.pts"
    path.write_text("Version 1.0\n3\nS0001 1.0 2.0 3.0\nS0002 9999 9999 9999\nS0003 -1 2 3\n")
    points = read_landmarks(path)
    assert points.names() == ["S0001", "S0002", "S0003"]
    assert [lm.placed for lm in points.landmarks] == [True, False, True]


@pytest.mark.parametrize("name, text, pattern", [
    ("bad.pp", "<PickedPoints><point x='a' y='0' z='0' name='p'/></PickedPoints>", r"bad.pp, point 1 \(p\): 'a' is not a number"),
    ("bad.pp", "<PickedPoints><point", r"not a valid PickPoints XML"),
    ("bad.pts", "Version 1.0\n3\nA 1 2 3\n", r"the count line says 3 points but 1 follow"),
    ("bad.csv", "a,b,c\n1,2,3\n", r"first row must name the columns name \(or label\), x, y, z"),
    ("bad.fcsv", "# CoordinateSystem = IJK\n", r"coordinate system 'IJK' is not LPS or RAS"),
    ("bad.mrk.json", "{}", r"not a Slicer markups file"),
    ("bad.txt", "", r"unknown landmark format; use one of .csv, .fcsv, .json, .mrk.json, .nts, .pp, .pts, .tps"),
    ("bad.tps", "LM=2\n1 2\n3 4\nID=a\n", r"line 1: LM= holds 2D landmarks; the filter needs 3D ones \(LM3=\)"),
    ("bad.tps", "LM3=3\n1 2 3\n4 5\n", r"line 3: LM3=3 needs 3 lines of x y z \(landmark 2 has 2 values\)"),
    ("bad.tps", "LM3=three\n", r"line 1: LM3='three' is not a count"),
    ("bad.tps", "ID=a\n", r"no LM3= block"),
    ("bad.tps", "LM3=1\n1 2 3\nSCALE=-2\n", r"line 3: SCALE=-2 must be positive"),
    ("bad.nts", "2 1 6 0 DIM=3\n1 2 3 4 5 6\n", r"the parameter line must start with 1"),
    ("bad.nts", "1 1 4 0 DIM=2\n1 2 3 4\n", r"DIM=2; the filter needs 3D landmarks \(DIM=3\)"),
    ("bad.nts", "1 1 6 0 DIM=3\n1 2 3 4 5\n", r"1 specimens of 6 values .* need 6 numbers after the labels, and 5 follow"),
    ("bad.nts", "1 one 6 0 DIM=3\n", r"line 1: the parameter line '1 one 6 0 DIM=3' is not"),
])
def test_unreadable_files_name_the_file_and_the_place(tmp_path, name, text, pattern):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(LandmarkFileError, match=pattern):
        read_landmarks(path)


def test_missing_file(tmp_path):
    with pytest.raises(LandmarkFileError, match=r"nothere.pp: cannot be read"):
        read_landmarks(tmp_path / "nothere.pp")


@pytest.mark.parametrize("name, text, pattern", [
    ("inf.csv", "name,x,y,z\na,inf,0,0\n", r"inf.csv, line 2: coordinate 'inf' is not finite"),
    ("short.pts", "A 1 2\n", r"short.pts, point 1: expected 'name x y z', got 'A 1 2'"),
    ("two.mrk.json", '{"markups": [{"controlPoints": [{"label": "a", "position": [1, 2]}]}]}',
     r"control point 1 \(a\): position must have 3 coordinates"),
    ("short.fcsv", "# CoordinateSystem = LPS\n# columns = id,x,y,z,label\n1,2,3,4,a\n2,5,6\n",
     r"short.fcsv, line 4: the row has 3 fields, too few for the x, y, z columns \(id, x, y, z\); complete or delete "
     r"the row"),
    ("scene.json", '{"nodes": []}', r'scene.json: not a Slicer markups file \(no "markups" list'),
    ("broken.json", '{"markups": [', r"broken.json: not valid JSON"),
    ("odd.json", '{"markups": [{"type": "Fiducial", "name": "skull", "controlPoints": {"label": "a"}}]}',
     r"odd.json: controlPoints of markup 'skull' is not a list"),
])
def test_more_malformed_files(tmp_path, name, text, pattern):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(LandmarkFileError, match=pattern):
        read_landmarks(path)


def test_an_fcsv_without_a_z_column_says_so(tmp_path):
    path = tmp_path / "no_z.fcsv"
    path.write_text("# Markups fiducial file version = 4.11\n# CoordinateSystem = LPS\n"
                    "# columns = id,x,y,ow,ox,oy,oz,vis,sel,lock,label\nvtkMRML_1,1,2,0,0,0,1,1,1,0,L_a\n")
    with pytest.raises(LandmarkFileError, match=r"no_z.fcsv, line 3: the columns header has no z column"):
        read_landmarks(path)


TPS_STUDY = """LM3=3
1.0 2.0 3.0
-1.0 2.0 3.0
0.0 4.0 NA
IMAGE=skull_A.ply
ID=UCMP-123
SCALE=0.5
COMMENT=field season 2019
LM3=3
2.0 2.0 3.0
-2.0 2.0 3.0
0.0 5.0 1.0
CURVES=1
POINTS=2
0.1 0.2 0.3
0.4 0.5 0.6
ID=UCMP-124
"""


def test_a_tps_study_one_specimen_chosen_by_id_or_index_scaled(tmp_path):
    path = tmp_path / "study.tps"
    path.write_text(TPS_STUDY)
    with pytest.warns(SymblendWarning, match=r"holds 2 specimens \(UCMP-123, UCMP-124\); the first \(UCMP-123\) is "
                                             r"used. Choose one with --specimen"):
        first = read_landmarks(path)
    assert first.names() == ["1", "2", "3"]
    assert first.landmarks[0].position == (0.5, 1.0, 1.5)  # SCALE=0.5 applied
    assert [lm.placed for lm in first.landmarks] == [True, True, False]  # NA: not placed
    second = read_landmarks(path, "UCMP-124")
    assert second.landmarks[2].position == (0.0, 5.0, 1.0)  # no SCALE line: 1
    assert read_landmarks(path, 2).landmarks == second.landmarks
    with pytest.raises(LandmarkFileError, match=r"study.tps: no specimen 'UCMP-9'; its specimens are UCMP-123, "
                                                r"UCMP-124 \(by ID, or by index 1..2\)"):
        read_landmarks(path, "UCMP-9")


def test_a_specimen_is_only_for_tps(tmp_path):
    path = tmp_path / "points.csv"
    write_landmarks(path, SAMPLE)
    with pytest.raises(LandmarkFileError, match=r"--specimen chooses a specimen of a .tps or .nts file"):
        read_landmarks(path, "1")


@pytest.mark.parametrize("missing", ["NA", "-999", "9999", "nan"])
@pytest.mark.parametrize("suffix, template", [
    (".csv", "name,x,y,z\nL_a,1,2,3\nR_a,{m},{m},{m}\n"),
    (".pts", "Version 1.0\n2\nL_a 1 2 3\nR_a {m} {m} {m}\n"),
    (".pp", '<!DOCTYPE PickedPoints>\n<PickedPoints><point x="1" y="2" z="3" name="L_a"/>'
            '<point x="{m}" y="{m}" z="{m}" name="R_a"/></PickedPoints>\n'),
    (".tps", "LM3=2\n1 2 3\n{m} {m} {m}\n"),
])
def test_missing_landmarks_as_the_field_writes_them(tmp_path, suffix, template, missing):
    path = tmp_path / f"points{suffix}"
    path.write_text(template.format(m=missing))
    assert [lm.placed for lm in read_landmarks(path).landmarks] == [True, False]


def test_a_whole_study_written_as_one_tps_file_reads_back_by_id(tmp_path):
    from filter_symblend.landmarks.formats import write_tps_study
    path = tmp_path / "study.tps"
    second = LandmarkSet([Landmark("a", (1.0, 2.0, 3.0)), Landmark("b", (0.0, 0.0, 0.0), placed=False)])
    write_tps_study(path, {"skull-1": SAMPLE, "skull-2": second})
    back = read_landmarks(path, "skull-2")
    assert [lm.position for lm in back.landmarks][:1] == [(1.0, 2.0, 3.0)]
    assert [lm.placed for lm in back.landmarks] == [True, False]
    assert [lm.position for lm in read_landmarks(path, 1).landmarks][:3] == [lm.position for lm in SAMPLE.landmarks[:3]]
    assert path.read_text().count("LM3=") == 2 and "NA NA NA" in path.read_text()


NTS_STUDY = '''" three skulls, 2 landmarks each, -999 for missing
1 2L 6 1 -999 DIM=3
skull_a skull_b
1.0 2.0 3.0 -1.0 2.0 3.0
4.0 5.0 6.0 -999 -999 -999
'''


def test_an_nts_study_one_specimen_by_label_or_index(tmp_path):
    path = tmp_path / "study.nts"
    path.write_text(NTS_STUDY)
    second = read_landmarks(path, "skull_b")
    assert second.names() == ["1", "2"] and second.landmarks[0].position == (4.0, 5.0, 6.0)
    assert [lm.placed for lm in second.landmarks] == [True, False]  # the file's own missing code
    assert read_landmarks(path, 1).landmarks[1].position == (-1.0, 2.0, 3.0)




# ---- Slicer's files as each version wrote them ------------------------------------------------

SLICER_FCSV = {
    "3.6": ("# Fiducial List file /data/skull.fcsv\n# version = 2\n# name = skull\n# numPoints = 3\n"
            "# symbolScale = 5\n# visibility = 1\n# color = 0.4,1,1\n# columns = label,x,y,z,sel,vis\n"
            "L_porion,-60,10.5,3,1,1\nR_porion,60,10.5,3,1,1\nnasion,0,-80,20,1,1\n"),
    "4.6": ("# Markups fiducial file version = 4.6\n# CoordinateSystem = 0\n"
            "# columns = id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID\n"
            "vtkMRMLMarkupsFiducialNode_0,-60,10.5,3,0,0,0,1,1,1,0,L_porion,,vtkMRMLModelNode4\n"
            "vtkMRMLMarkupsFiducialNode_1,60,10.5,3,0,0,0,1,1,1,0,R_porion,,vtkMRMLModelNode4\n"
            "vtkMRMLMarkupsFiducialNode_2,0,-80,20,0,0,0,1,1,1,0,nasion,,vtkMRMLModelNode4\n"),
    "4.11": ("# Markups fiducial file version = 4.11\n# CoordinateSystem = 1\n"
             "# columns = id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID\n"
             "1,60,-10.5,3,0,0,0,1,1,1,0,L_porion,,\n2,-60,-10.5,3,0,0,0,1,1,1,0,R_porion,,\n"
             "3,0,80,20,0,0,0,1,1,1,0,nasion,,\n"),
    "5.0": ("# Markups fiducial file version = 5.0\n# CoordinateSystem = LPS\n"
            "# columns = id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID\n"
            "1,60,-10.5,3,0,0,0,1,1,1,0,L_porion,,\n2,-60,-10.5,3,0,0,0,1,1,1,0,R_porion,,\n"
            "3,0,80,20,0,0,0,1,1,1,0,nasion,,\n"),
    # 5.6: rows carry two fields the header does not name; an unplaced point with empty coordinates
    "5.6": ("# Markups fiducial file version = 5.6\n# CoordinateSystem = RAS\n"
            "# columns = id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID\n"
            "1,-60,10.5,3,0,0,0,1,1,1,0,L_porion,,,2,0\n2,60,10.5,3,0,0,0,1,1,1,0,R_porion,,,2,0\n"
            "3,0,-80,20,0,0,0,1,1,1,0,nasion,,,2,0\n4,,,,0,0,0,1,1,1,0,,,,2,0\n"),
}


@pytest.mark.parametrize("version", SLICER_FCSV)
def test_an_fcsv_of_every_slicer_version_reads_to_the_same_points(tmp_path, version):
    path = tmp_path / f"slicer{version}.fcsv"
    path.write_text(SLICER_FCSV[version])
    written = path.read_bytes()
    points, _ = read_landmarks(path).in_frame("LPS")
    assert points.names()[:3] == ["L_porion", "R_porion", "nasion"]
    assert [lm.position for lm in points.landmarks[:3]] == [(60.0, -10.5, 3.0), (-60.0, -10.5, 3.0), (0.0, 80.0, 20.0)]
    assert all(lm.placed for lm in points.landmarks[:3])
    if version == "5.6":
        assert points.landmarks[3].name == "F-4" and not points.landmarks[3].placed
    assert path.read_bytes() == written


TWO_MARKUPS = json.dumps({
    "@schema": "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/Resources/Schema/"
               "markups-schema-v1.0.3.json#",
    "markups": [
        {"type": "Fiducial", "name": "skull", "coordinateSystem": "LPS", "controlPoints": [
            {"id": "1", "label": "skull-1", "position": [60, -10.5, 3], "positionStatus": "defined"},
            {"id": "2", "label": "skull-2", "position": [-60, -10.5, 3], "positionStatus": "defined"}]},
        {"type": "Curve", "coordinateSystem": "RAS", "controlPoints": [
            {"id": "1", "label": "", "position": [0, 1, 2], "positionStatus": "defined"},
            {"id": "2", "position": [0, 2, 3], "positionStatus": "defined"}]},
    ]})


@pytest.mark.parametrize("name", ["skull.json", "skull.mrk.json", "skull_landmarks.txt"])
def test_a_markups_json_is_recognised_by_its_content_and_one_markup_chosen(tmp_path, name):
    path = tmp_path / name
    path.write_text(TWO_MARKUPS)
    with pytest.warns(SymblendWarning, match=r"holds 2 markups \(skull, Curve 2\); the first \(skull\) is used. "
                                             r"Choose one with --specimen"):
        first = read_landmarks(path)
    assert first.names() == ["skull-1", "skull-2"] and first.coordinate_system == "LPS"
    assert read_landmarks(path, specimen="skull").names() == ["skull-1", "skull-2"]
    curve = read_landmarks(path, specimen=2)
    assert curve.names() == ["curve-1", "curve-2"] and curve.coordinate_system == "RAS"
    assert find_curves(curve.names(), midline=True)[0][0].left == [0, 1]
    with pytest.raises(LandmarkFileError, match=r"no markup 'face'; its markups are skull, Curve 2 \(by name, or by "
                                                r"index 1..2\)"):
        read_landmarks(path, specimen="face")


def test_specimen_on_a_file_of_one_set_is_refused(tmp_path):
    one = tmp_path / "one.fcsv"
    one.write_text(SLICER_FCSV["5.0"])
    with pytest.raises(LandmarkFileError, match="--specimen chooses a specimen of a .tps or .nts file, or a markup of "
                                                "a Slicer markups JSON; this file holds one set of landmarks"):
        read_landmarks(one, specimen=2)


def test_a_binary_file_is_refused(tmp_path):
    binary = tmp_path / "scan.fcsv"
    binary.write_bytes(b"\xff\xfe\x00\x81binary")
    with pytest.raises(LandmarkFileError, match=r"scan.fcsv: not a text file; landmark files are text \(.csv, "):
        read_landmarks(binary)
