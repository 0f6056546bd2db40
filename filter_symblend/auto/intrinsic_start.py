"""When no map mirrors enough of the surface of a posed body: the intrinsic mirror's own vertex pairs, solved, as
the first output (in ``mode='articulated'`` only: the intrinsic mirror holds under isometries, a pose, and not
under a compression, where it pairs wrongly and the rounds cannot tell).

A body whose limbs are swung far (FAUST's most posed humans, a crouching man) defeats every extrinsic
map, and the intrinsic mirror used as a map of space (:mod:`.intrinsic_map`) mixes parts that touch (an
arm along the torso). Its vertex pairs themselves are mostly right, for some sizes of the first
functional map and not for others (the sign solve of :func:`.spectral.mirror_functional_map` is
sensitive to the basis size when the pose is strong: a size may give another near-symmetry, or a map
that folds a limb onto itself). So each size of :data:`.spectral.STARTS` gives a vertex map, refined by ZoomOut,
and (:func:`.spectral.candidate_mirrors`):

- the shape must be intrinsically symmetric: the map keeps the heat kernel signatures,
  ``median |log HKS(x) - log HKS(m(x))|`` at most ``DESCRIPTOR_AGREEMENT`` x the same median between
  random vertices. A mirror found by the sign solve on a shape that has none (a bunny, a CAD part) leaves
  them unequal;
- of the maps that keep them, and of the best three refitted on their continuous parts, the one that mirrors
  the most of the surface (:func:`.spectral.mirrored_share`: a mirror sends each triangle onto a triangle of
  opposite orientation, and neighbours onto neighbours) is chosen (docs/automatic-pairs.md);
- its mutual pairs whose sides lie apart (``APART`` of the diagonal), ``PAIRS`` of them spread evenly,
  each from its left side, are solved by the paper's method (a map whose pairs cannot be solved gives way
  to the next by the same score). Whether the output is more symmetric about a plane than the input is
  not asked: on a strongly posed body it is not, even from the right pairs (tr_reg_088: the most accurate
  map's output, 15.9 -> 15.3 % over the ground-truth twins, is 10 % less symmetric about its plane).

The rounds then pair that output again, where extrinsic maps work (:mod:`.rounds`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..core.mirror_pairs import spread_left_sides
from ..core.solve import SymmetrizationResult
from ..errors import SymblendError
from .config import AutoConfig
from .intrinsic_map import input_vertices, spectral_candidates
from .spectral import DESCRIPTOR_AGREEMENT
from .surface import Surface

PAIRS = 300  # pairs solved per start: a coarse intrinsic map gives a few hundred sound ones on a 5,000-vertex body


def intrinsic_start(surface: Surface, config: AutoConfig, solve_pairs: Callable[[np.ndarray, np.ndarray], SymmetrizationResult],
                    asymmetry_of: Callable[[SymmetrizationResult], float]):
    """(the output of the chosen intrinsic vertex pairs, what was tried) or (None, what was tried); see the
    module doc. ``solve_pairs(left, right)``: the paper's solve on vertex pairs of the input;
    ``asymmetry_of(result)``: an output's mirror asymmetry (reported for the chosen map)."""
    tried = {"starts": {}}
    if not surface.is_mesh:
        return None, tried
    mesh, candidates = spectral_candidates(surface, config)
    if candidates is None:
        return None, tried
    for candidate in sorted(candidates, key=lambda mirror: (mirror.size, mirror.start)):
        entry = tried["starts"][candidate.name] = {"descriptor_disagreement": candidate.descriptor_disagreement}
        if candidate.keeps_descriptors:
            entry["mirrored_share"] = candidate.mirrored_share
    vertex_of = input_vertices(surface, mesh)
    for candidate in filter(lambda mirror: mirror.keeps_descriptors, candidates):
        vertex_map = candidate.vertex_map
        entry = tried["starts"][candidate.name]
        mutual = vertex_map[vertex_map] == np.arange(len(vertex_map))
        left = spread_left_sides(mesh.points, mesh.points[vertex_map], mutual, PAIRS, surface.diagonal)
        left, right = vertex_of[left], vertex_of[vertex_map[left]]
        distinct = left != right
        entry["pairs"] = int(np.count_nonzero(distinct))
        if entry["pairs"] < 4:
            continue
        try:
            result = solve_pairs(left[distinct], right[distinct])
        except SymblendError as error:  # pairs that fall apart, or a degenerate neighbourhood: not this map
            entry["refused"] = str(error)
            continue
        entry["surface_asymmetry"] = asymmetry_of(result)
        tried["chosen"] = candidate.name
        return result, tried
    return None, tried


def cannot_start(tried: dict) -> str:
    """Why the intrinsic pairs gave no first output, in one sentence (for the refusal's message)."""
    starts = tried["starts"]
    if not starts:
        return "The shape's intrinsic mirror could not be computed (a point cloud, or no spectrum)."
    least = min(entry["descriptor_disagreement"] for entry in starts.values())
    if least > DESCRIPTOR_AGREEMENT:
        return (f"Its intrinsic mirror does not keep the shape's heat kernel signatures (disagreement {least:.2f}, "
                f"a symmetric shape {DESCRIPTOR_AGREEMENT:g} or less): the shape has no intrinsic mirror symmetry.")
    reason = next((entry["refused"] for entry in starts.values() if "refused" in entry), "too few pairs apart")
    return f"Its intrinsic mirror's pairs could not be solved ({reason})."
