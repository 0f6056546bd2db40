"""Pairing by name and by table; snapping to vertices."""

import numpy as np
import pytest

from filter_symblend import LandmarkError, SymblendWarning
from filter_symblend.landmarks.formats import Landmark, LandmarkFileError, LandmarkSet
from filter_symblend.landmarks.pairing import pair_by_name, read_pair_table, snap_pairs
from filter_symblend.meshlab.attributes import pair_labels


def test_pairing_by_name_conventions():
    names = ["L_orbitale", "Orbitale_R", "left-porion", "PORION RIGHT", "zygion.l", "Zygion.r", "nasion",
             "Lt_gonion", "rt_gonion"]
    pairs, unpaired = pair_by_name(names)
    assert sorted(pairs) == [(0, 1), (2, 3), (4, 5), (7, 8)]
    assert unpaired == [6]


def test_a_side_without_partner_is_unpaired_and_a_duplicate_is_an_error():
    assert pair_by_name(["L_a", "R_a", "L_b"]) == ([(0, 1)], [2])
    with pytest.raises(LandmarkError, match=r"'L_a' and 'left_a' are both the left 'a'; rename one"):
        pair_by_name(["L_a", "left_a", "R_a"])


def test_custom_side_words():
    pairs, unpaired = pair_by_name(["sin_a", "dex_a"], left_words=("sin",), right_words=("dex",))
    assert pairs == [(0, 1)] and unpaired == []


def test_pair_table_by_names_and_by_numbers(tmp_path):
    names = ["a1", "b1", "a2", "b2"]
    table = tmp_path / "pairs.csv"
    table.write_text("left,right\na1,b1\na2,b2\n")
    assert read_pair_table(table, names) == [(0, 1), (2, 3)]
    table.write_text("1,2\n3,4\n")
    assert read_pair_table(table, names) == [(0, 1), (2, 3)]
    table.write_text("1,2\n3,9\n")
    with pytest.raises(LandmarkFileError, match=r"line 2: landmark number 9 does not exist \(the landmark file has 4"):
        read_pair_table(table, names)
    table.write_text("a1,b1\na2,zz\n")
    with pytest.raises(LandmarkFileError, match=r"line 2: no landmark is named 'zz'"):
        read_pair_table(table, names)


def grid_points():
    return np.array([[x, y, z] for x in (-1.0, 1.0) for y in (0.0, 1.0, 2.0) for z in (0.0, 1.0)])


def test_snapping_reports_distances_and_skips_unplaced_pairs():
    points = grid_points()
    landmarks = LandmarkSet([Landmark("L_a", (1.0, 0.05, 0.0)), Landmark("R_a", (-1.0, 0.0, 0.02)),
                             Landmark("L_b", (1.0, 2.0, 1.0)), Landmark("R_b", (0, 0, 0), placed=False)])
    with pytest.warns(SymblendWarning, match=r"L_b/R_b have a landmark marked as not placed"):
        snapped = snap_pairs(points, landmarks, [(0, 1), (2, 3)], [])
    assert snapped.pairs.left.tolist() == [6] and snapped.pairs.right.tolist() == [0]
    np.testing.assert_allclose(snapped.snap_distances, [[0.05, 0.02]])
    np.testing.assert_array_equal(pair_labels(len(points), snapped.pairs)[[6, 0]], [1, -1])


def test_snapping_errors_and_warnings():
    points = grid_points()
    clash = LandmarkSet([Landmark("L_a", (1.0, 0.0, 0.0)), Landmark("R_a", (-1.0, 0.0, 0.0)),
                         Landmark("L_b", (1.0, 0.01, 0.0)), Landmark("R_b", (-1.0, 2.0, 1.0))])
    with pytest.raises(LandmarkError, match=r"landmarks 'L_a' and 'L_b' both snap to vertex 6"):
        snap_pairs(points, clash, [(0, 1), (2, 3)], [])
    with pytest.raises(LandmarkError, match=r"1 landmark\(s\) have no partner: 'nasion'.*\(--midline\)"):
        snap_pairs(points, LandmarkSet([Landmark("nasion", (0, 0, 0))]), [], [0])
    far = LandmarkSet([Landmark("L_a", (1.0, 0.0, -5.0)), Landmark("R_a", (-1.0, 0.0, 0.0))])
    with pytest.raises(LandmarkError, match=r"L_a \(5\) lie far from the mesh surface.*--mesh-frame.*"
                                             r"--allow-far-landmarks"):
        snap_pairs(points, far, [(0, 1)], [])
    with pytest.warns(SymblendWarning, match=r"L_a \(5\) lie far from the mesh surface.*--mesh-frame"):
        snap_pairs(points, far, [(0, 1)], [], allow_far=True)


def test_unpaired_landmarks_become_midline_landmarks_when_asked():
    points = np.vstack([grid_points(), [0.0, 1.0, 0.5]])
    landmarks = LandmarkSet([Landmark("L_a", (1.0, 0.0, 0.0)), Landmark("R_a", (-1.0, 0.0, 0.0)),
                             Landmark("nasion", (0.0, 1.0, 0.45))])
    snapped = snap_pairs(points, landmarks, [(0, 1)], [2], midline=True)
    assert snapped.pairs.midline.tolist() == [12] and snapped.midline_names == ["nasion"]
    assert snapped.weights(["R_a"])[1].tolist() == [0.0]
    with pytest.raises(LandmarkError, match=r"--missing names 'R_b', which no pair has"):
        snapped.weights(["R_b"])


def test_pair_table_errors(tmp_path):
    table = tmp_path / "pairs.csv"
    table.write_text("a1\n")
    with pytest.raises(LandmarkFileError, match=r"line 1: expected two columns \(left, right\)"):
        read_pair_table(table, ["a1"])
    with pytest.raises(LandmarkFileError, match=r"none.csv: cannot be read"):
        read_pair_table(tmp_path / "none.csv", ["a1"])
