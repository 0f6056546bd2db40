"""Landmark attributes on a MeshSet mesh: written, read back, honoured by the filter; their errors."""

import numpy as np
import pymeshlab
import pytest

import filter_symblend
from filter_symblend import LandmarkError
from filter_symblend.core.landmark_pairs import LandmarkPairs
from filter_symblend.meshlab.attributes import read_landmark_attributes, write_landmark_attributes
from filter_symblend.testing import synthetic

from test_ground_truth import midline_vertices
from test_validation import assert_unchanged, cube_pairs, snapshot


def meshset(points, faces=None):
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=points, face_matrix=faces) if faces is not None
                else pymeshlab.Mesh(vertex_matrix=points))
    return ms


def test_attributes_round_trip(cow):
    left, right = cow.landmarks(40)
    pairs = LandmarkPairs(np.arange(1, 41), left, right, midline_vertices(cow, 5))
    weights = np.linspace(0, 1, 40)
    ms = meshset(cow.points, cow.faces)
    write_landmark_attributes(ms.current_mesh(), pairs, right_weights=weights)
    back = read_landmark_attributes(ms.current_mesh())
    wl, wr = back.left_weights, back.right_weights
    np.testing.assert_array_equal(back.left, left)
    np.testing.assert_array_equal(back.right, right)
    np.testing.assert_array_equal(np.sort(back.midline), np.sort(pairs.midline))
    np.testing.assert_array_equal(wl, 1.0)
    np.testing.assert_allclose(wr, weights)


def test_filter_honours_midline_and_weights_like_the_core(cow):
    left, right = cow.landmarks(100)
    midline = midline_vertices(cow, 8)
    weights = np.ones(100)
    weights[:5] = 0.0
    deformed = synthetic.bend(cow.points, 1.0)
    ms = meshset(deformed, cow.faces)
    write_landmark_attributes(ms.current_mesh(), LandmarkPairs(np.arange(1, 101), left, right, midline),
                              left_weights=weights)
    report = ms.generate_symmetrized_mesh()
    core = filter_symblend.symmetrize(deformed, left, right, None, np.sort(midline), weights, None)
    np.testing.assert_array_equal(ms.current_mesh().vertex_matrix(), core.points)
    assert report["midline_count"] == 8
    out = ms.current_mesh()
    for name in ("symblend_pair", "symblend_midline", "symblend_weight"):
        np.testing.assert_array_equal(out.vertex_custom_scalar_attribute_array(name),
                                      ms.mesh(0).vertex_custom_scalar_attribute_array(name))


@pytest.mark.parametrize("weights, pattern", [
    ((np.full(8, 1.5), None), r"`left_weights` must lie in \[0, 1\]; pair 1 has 1.5"),
    ((np.r_[0.0, np.ones(7)], np.r_[0.0, np.ones(7)]), r"Pair 1 has weight 0 on both sides"),
    ((np.ones(7), None), r"`left_weights` must have one weight per pair \(8\), got 7"),
])
def test_bad_weights(weights, pattern):
    points, left, right = cube_pairs()
    with pytest.raises(LandmarkError, match=pattern):
        filter_symblend.symmetrize(points, left, right, left_weights=weights[0], right_weights=weights[1])


def test_midline_errors():
    points, left, right = cube_pairs()
    points = np.vstack([points, [0.0, 0.5, 0.5]])
    with pytest.raises(LandmarkError, match=r"Vertex 3 is used by two landmarks \(\+4 and midline 1\)"):
        filter_symblend.symmetrize(points, left, right, midline=[3])
    ms = meshset(points)
    labels = np.zeros(17)
    labels[left], labels[right] = np.arange(1, 9), -np.arange(1, 9)
    ms.current_mesh().add_vertex_custom_scalar_attribute(labels, "symblend_pair")
    ms.current_mesh().add_vertex_custom_scalar_attribute(np.eye(17)[16], "symblend_midline")
    weights = np.ones(17)
    weights[16] = 0.5
    ms.current_mesh().add_vertex_custom_scalar_attribute(weights, "symblend_weight")
    before = snapshot(ms)
    with pytest.raises(LandmarkError, match=r"Midline landmark on vertex 16 has weight 0.5 .*set 1"):
        ms.generate_symmetrized_mesh()
    assert_unchanged(ms, before)
