"""Landmarks as per-vertex custom scalar attributes of a pymeshlab mesh: write and read.

Encodings (attribute names are the filter's parameters; defaults shown):
- ``symblend_pair``: +k on the left vertex of pair k, -k on the right one, 0 elsewhere.
- ``symblend_midline``: non-zero on midline landmarks (they end up on the symmetry plane).
- ``symblend_weight``: in [0, 1] at each landmark (1 elsewhere); 0 marks a missing or
  broken landmark, whose side then takes the mirror shape of the other side.
Midline and weight attributes are optional.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pymeshlab

from ..core.landmark_pairs import LandmarkPairs
from ..errors import LandmarkError, id_list
from ..parameters import DEFAULTS


def optional_attribute(mesh: pymeshlab.Mesh, name: str) -> np.ndarray | None:
    """The per-vertex custom scalar attribute ``name`` (N,), or None when the mesh has none."""
    try:
        return mesh.vertex_custom_scalar_attribute_array(name)
    except pymeshlab.PyMeshLabException:
        return None


def custom_attribute_names(ms: pymeshlab.MeshSet) -> dict[str, list[str]]:
    """Custom attributes of the current mesh by kind: 'vs', 'vp', 'fs', 'fp' (vertex/face, scalar/point).

    pymeshlab cannot list them directly; its PLY exporter's parameters name them.
    """
    names = {"vs": [], "vp": [], "fs": [], "fp": []}
    for key in ms.filter_parameter_values("ply"):
        if key.startswith("__ca_") and key[5:7] in names and key[7:9] == "__":
            names[key[5:7]].append(key[9:])
    return names


def pair_labels(n_vertices: int, pairs: LandmarkPairs) -> np.ndarray:
    """The pair attribute (N,): +k on left vertices, -k on right ones, 0 elsewhere."""
    labels = np.zeros(n_vertices)
    labels[pairs.left], labels[pairs.right] = pairs.ids, -pairs.ids
    return labels


def landmark_attribute_values(n_vertices: int, pairs: LandmarkPairs, names: tuple[str, str, str],
                              left_weights=None, right_weights=None) -> dict[str, np.ndarray]:
    """The attributes that encode ``pairs`` on a mesh of ``n_vertices``: {name: (N,)} for the pair
    attribute, the midline attribute when there are midline landmarks and the weight attribute when weights
    are given; ``names``: (pair, midline, weight) attribute names."""
    pair_attribute, midline_attribute, weight_attribute = names
    values = {pair_attribute: pair_labels(n_vertices, pairs)}
    if len(pairs.midline):
        midline = np.zeros(n_vertices)
        midline[pairs.midline] = np.arange(1, len(pairs.midline) + 1)
        values[midline_attribute] = midline
    if left_weights is not None or right_weights is not None:
        weights = np.ones(n_vertices)
        weights[pairs.left] = 1.0 if left_weights is None else left_weights
        weights[pairs.right] = 1.0 if right_weights is None else right_weights
        values[weight_attribute] = weights
    return values


def write_landmark_attributes(mesh: pymeshlab.Mesh, pairs: LandmarkPairs, left_weights=None,
                              right_weights=None, pair_attribute: str = DEFAULTS["pair_attribute"],
                              midline_attribute: str = DEFAULTS["midline_attribute"],
                              weight_attribute: str = DEFAULTS["weight_attribute"]) -> None:
    """Add the pair attribute, and the midline and weight attributes when there are any, to
    ``mesh`` (a mesh of a MeshSet: add attributes after ``ms.add_mesh``, not before)."""
    names = (pair_attribute, midline_attribute, weight_attribute)
    for name, values in landmark_attribute_values(mesh.vertex_number(), pairs, names, left_weights,
                                                  right_weights).items():
        mesh.add_vertex_custom_scalar_attribute(values, name)


def pairs_from_attribute(values: np.ndarray, attribute: str) -> LandmarkPairs:
    """Decode the pair attribute ``values`` (N,) into pairs sorted by label k."""
    values = np.asarray(values, dtype=float)
    if not np.isfinite(values).all():
        raise LandmarkError(
            f"Attribute `{attribute}` is not finite at vertex {id_list(np.flatnonzero(~np.isfinite(values)))}; "
            "set those vertices to 0 (no landmark) or to a pair label +k / -k."
        )
    labels = np.rint(values)
    fractional = labels != values
    if fractional.any():
        v = np.flatnonzero(fractional)[0]
        raise LandmarkError(
            f"Attribute `{attribute}` holds {values[v]:g} at vertex {v}; pair labels are whole "
            "numbers (+k on the left vertex, -k on the right one, 0 elsewhere)."
        )
    labels = labels.astype(np.int64)
    sides = {}
    for name, sign in (("left", 1), ("right", -1)):
        vertices = np.flatnonzero(sign * labels > 0)
        ids = sign * labels[vertices]
        unique, counts = np.unique(ids, return_counts=True)
        if (counts > 1).any():
            k = unique[counts > 1][0]
            raise LandmarkError(
                f"Pair label {sign * k:+d} is used on {counts[unique == k][0]} vertices "
                f"({id_list(np.flatnonzero(sign * labels == k))}) of attribute `{attribute}`; each label "
                f"must appear once as +{k} and once as -{k}. Renumber the extra ones."
            )
        sides[name] = dict(zip(ids.tolist(), vertices.tolist()))
    for here, there, sign in (("left", "right", 1), ("right", "left", -1)):
        orphans = sorted(set(sides[here]) - set(sides[there]))
        if orphans:
            k = orphans[0]
            raise LandmarkError(
                f"Pair {k}: {sign * k:+d} on vertex {sides[here][k]} has no {-sign * k:+d} partner "
                f"in attribute `{attribute}`"
                + (f" (also unpaired: {', '.join(map(str, orphans[1:11]))})" if len(orphans) > 1 else "")
                + f". Put {-sign * k:+d} on the {there} vertex, or set {sign * k:+d} to 0."
            )
    ids = np.array(sorted(sides["left"]), dtype=np.int64)
    return LandmarkPairs(
        ids,
        np.array([sides["left"][k] for k in ids], dtype=np.int64),
        np.array([sides["right"][k] for k in ids], dtype=np.int64),
    )


def read_attributes(mesh: pymeshlab.Mesh, names) -> dict[str, np.ndarray]:
    """{name: (N,) values} of the per-vertex custom scalar attributes among ``names`` that ``mesh`` has, each
    read once."""
    return {name: values for name in names if (values := optional_attribute(mesh, name)) is not None}


def read_landmark_attributes(mesh: pymeshlab.Mesh, pair_attribute: str = DEFAULTS["pair_attribute"],
                             midline_attribute: str = DEFAULTS["midline_attribute"],
                             weight_attribute: str = DEFAULTS["weight_attribute"]) -> LandmarkPairs:
    """The pairs of ``mesh``, with their midline landmarks and weights (all 1 where the mesh has none)."""
    names = (pair_attribute, midline_attribute, weight_attribute)
    return landmarks_from_attributes(read_attributes(mesh, names), mesh.label(), *names)


def landmarks_from_attributes(found: dict[str, np.ndarray], label: str, pair_attribute: str,
                              midline_attribute: str, weight_attribute: str) -> LandmarkPairs:
    """The pairs in the attributes ``found`` ({name: (N,)}, as :func:`read_attributes` gives them) of the
    mesh labelled ``label``, with their midline landmarks and weights."""
    values = found.get(pair_attribute)
    if values is None:
        raise LandmarkError(
            f"The current mesh ('{label}') has no per-vertex custom scalar attribute "
            f"`{pair_attribute}`. Add the pairs first: "
            f"ms.current_mesh().add_vertex_custom_scalar_attribute(labels, '{pair_attribute}') with "
            "+k on the left vertex of pair k, -k on the right one and 0 elsewhere (or "
            "filter_symblend.meshlab.attributes.write_landmark_attributes), or name your attribute "
            "with `pair_attribute`.")
    pairs = pairs_from_attribute(values, pair_attribute)
    midline_values = found.get(midline_attribute)
    if midline_values is not None:
        pairs = LandmarkPairs(pairs.ids, pairs.left, pairs.right, np.flatnonzero(midline_values))
    weights = found.get(weight_attribute)
    if weights is None:
        return pairs
    off = pairs.midline[weights[pairs.midline] != 1]
    if off.size:
        raise LandmarkError(f"Midline landmark on vertex {off[0]} has weight {weights[off[0]]:g} in "
                            f"`{weight_attribute}`; midline landmarks take no weight (set 1).")
    return dataclasses.replace(pairs, left_weights=weights[pairs.left], right_weights=weights[pairs.right])
