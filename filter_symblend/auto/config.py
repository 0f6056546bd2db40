"""What stays tunable in the automatic pairs: one frozen object, each field with its unit and reason.

The defaults are properties of the method (statistics, geometry), not numbers read
off one mesh; docs/automatic-pairs.md records what they give on the corpus.
"""

from __future__ import annotations

import dataclasses

from ..measures.verdict import PART_LEFT_ASYMMETRIC


def _field(default, unit: str, reason: str):
    return dataclasses.field(default=default, metadata={"unit": unit, "reason": reason})


@dataclasses.dataclass(frozen=True)
class AutoConfig:
    """Settings of ``pairs='auto'`` and ``'landmarks+auto'``; ``AutoConfig.describe()`` lists them."""

    landing_tolerance: float = _field(
        0.01, "x bounding-box diagonal",
        "a vertex is mirrored by a map when its predicted twin lies this close to the surface (and the map "
        "comes back): one percent of the object's size, the asymmetry of a scan of a symmetric object")
    min_coverage: float = _field(
        0.75, "share of the surface",
        "below this share of mirrored vertices there is no mirror symmetry to restore: a shape a quarter "
        "of whose surface has no mirror image is refused, not made into another shape (a side cut away "
        "by up to 40 % still passes)")
    plane_suffices: float = _field(
        0.95, "share of the surface",
        "when a candidate map already mirrors this much of a surface that a plane mirrors min_coverage of (a rigid "
        "pose, a scan), no other could mirror much more: the costlier candidates are not tried (what is left is a "
        "strip along the midline and the scan's own asymmetry)")
    field_precision: float = _field(
        0.25, "x landing_tolerance",
        "a registered field is fitted onto the surface, so much of any shape lands within the landing "
        "tolerance (80 % of a bunny); a symmetry's images land within the field's own precision, a chance "
        "fit's spread over the whole tolerance: unless a plain map mirrors min_coverage (a scan, whose asymmetry "
        "fills the tolerance), a field must mirror precise_coverage within this share of it")
    precise_coverage: float = _field(
        0.65, "share of the surface",
        "what a registered field must mirror within field_precision of the landing tolerance: chosen between "
        "pymeshlab's bunny (58 %) and the remeshed cow bent 1.2 rad (72 %), checked on the Stanford bunny "
        "(53 %)")
    field_suffices: float = _field(
        0.98, "share of the surface",
        "plane_suffices of a shape no plane mirrors min_coverage of (a strong bend, a pose), and of any shape in "
        "articulated mode: there a registered field can mirror 95 % and still slide (the remeshed spot bent 0.6 "
        "rad: 0.69x the landmarks' symmetry error when the search goes on to 98 %, 1.57x when it stops at 95 %), "
        "and a plane that mirrors 95 % of a posed body can leave a swung limb unpaired (the remeshed spot's leg "
        "swung 0.3 rad: 1.48x -> 0.73x, the intrinsic mirror chosen)")
    local_precision: float = _field(
        10.0, "x the neighbouring pairs' median misfit",
        "a vertex pair must fit the local mirror map of its neighbours nearly as well as they fit their own: "
        "misfits are heavy-tailed where the curvature changes, while a vertex without an exact twin among "
        "exact pairs misses by orders of magnitude")
    local_neighbours: int = _field(
        12, "pairs",
        "pairs fitting each local affine mirror map: the fewest that determine an affine map (4) with "
        "room for noise, few enough to stay local (the growth of exact vertex pairs, which carry no noise, "
        "fits growth.GROWTH_NEIGHBOURS)")
    vertex_share: float = _field(
        0.75, "share of the usable vertices",
        "the vertices are taken to mirror each other when the exact-vertex growth pairs this share of them, "
        "as much as a map must mirror to be a symmetry (min_coverage): from chance twins on two sides sampled "
        "independently it stops near half, since their vertices miss each other's local maps")
    samples: int = _field(
        10_000, "vertices",
        "at most this many vertices, spread over the surface, are paired in each round: enough to choose "
        "the default auto_pair_count pairs from (one side of them), and the cost of a round stays bounded on "
        "million-vertex meshes")
    score_samples: int = _field(
        4000, "vertices",
        "vertices, spread over the surface, on which maps and outputs are compared: a share of the surface is "
        "measured on them to about 1 %")
    round_pairs: int = _field(
        1000, "pairs",
        "pairs of each round but the last: the rounds only have to find the twins, and the warp's cost grows "
        "with the cube of the pairs; the last solve takes auto_pair_count, and so does a round whose map pairs "
        "plane_suffices of the sample (it is the last)")
    least_gain: float = _field(
        0.05, "share of the output's mirror asymmetry",
        "a round that makes the output less than 5 % more mirror-symmetric than the round before is the "
        "last: the rounds converge geometrically, and the next would gain less still")
    coincident: float = _field(
        1e-9, "x bounding-box diagonal",
        "positions closer than this are one position (rounding); also the least precision a map is asked for")
    part_left_asymmetric: float = _field(
        PART_LEFT_ASYMMETRIC, "x bounding-box diagonal",
        "in articulated mode, an output from a map of space whose 99th percentile of distance to its own "
        "reflection exceeds this has a part left asymmetric (a limb no smooth map followed), and the intrinsic "
        "start is tried too: about the geometric middle (1.8 %) of the remeshed cow's unrestored swung legs "
        "(3.2 and 8.3 %) and the restored bends and legs of it and of spot (at most 1.0 %); checked on the BCICP "
        "shapes paired by maps of space (sound: at most 1.6 %; four TOSCA dogs above it, 4.5-12.5 %). The "
        "before/after checks warn of an output left so by the same bound (measures/verdict)")
    spectral_vertices: int = _field(
        6000, "vertices",
        "the intrinsic mirror is computed on a mesh of at most about this many vertices (larger ones are "
        "coarsened by vertex clustering): its 60-100 eigenfunctions vary over dozens of vertices, and the "
        "eigensolver's cost grows faster than the size")
    zoomout_sizes: tuple = _field(
        ((60, 6), (100, 8)), "(eigenfunctions, eigenfunctions per step)",
        "sizes the intrinsic map is refined to by ZoomOut, each with its step: each first map gives a candidate "
        "at each size, and the one that mirrors the most of the surface is taken; coarse enough that a bend "
        "leaves them nearly unchanged, fine enough to tell a hand from the hip it rests on (60 alone and 100 "
        "alone were each best on some shapes: chosen on half of 58 BCICP shapes, checked on the other half, "
        "docs/benchmarks.md)")
    pair_consistency: float = _field(
        0.02, "x bounding-box diagonal",
        "an intrinsic vertex pair is used (as a map, or to start a mirror field) only if the map sends the "
        "twin back within this of the vertex (twice an intrinsic map's typical error on a bent shape)")
    field_centres: int = _field(
        200, "kernel centres",
        "Gaussian centres of a mirror field, spread over the surface: a few per kernel width in each direction "
        "at the finest width (its registration's cost grows with their square)")
    field_widths: tuple = _field(
        (0.3, 0.15), "x bounding-box diagonal",
        "kernel widths of a mirror field, coarse to fine: the first follows a bend of the whole shape without "
        "being misled by the rough map's local errors, the second a swung limb or a bend's ends")
    field_iterations: int = _field(
        10, "ICP iterations per width",
        "iterations of a mirror field's registration at each width: point-to-plane ICP lands the images on the "
        "surface in a few; what they slide along it afterwards the involution's weight and the ridge decide "
        "(auto/field.py)")
    screening_samples: int = _field(
        800, "vertices",
        "vertices on which each candidate map is registered before they are compared (the winner is "
        "registered again on registration_samples)")
    screening_centres: int = _field(
        100, "kernel centres",
        "centres of a candidate's field while candidates are compared: at the coarse width, a hundred "
        "follow any bend")
    registration_samples: int = _field(
        1500, "vertices",
        "vertices the winning mirror field is registered on: enough for every kernel centre to see several "
        "of them within a width")

    @classmethod
    def describe(cls) -> str:
        """The fields as Markdown table rows: name, default, unit, reason."""
        rows = ["| field | default | unit | reason |", "|---|---|---|---|"]
        for field in dataclasses.fields(cls):
            rows.append(f"| `{field.name}` | {field.default!r} | {field.metadata['unit']} | {field.metadata['reason']} |")
        return "\n".join(rows)


DEFAULT = AutoConfig()
