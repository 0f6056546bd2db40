"""What stays tunable in the automatic pairs: one frozen object, each field with its unit and reason.

The defaults are properties of the method (statistics, geometry), not numbers read
off one mesh; docs/automatic-pairs.md records what they give on the corpus.
"""

from __future__ import annotations

import dataclasses


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
        "when one plane already mirrors this much of the surface, no non-rigid map can mirror much more: "
        "the affine and registered maps are not tried (speed)")
    ratio: float = _field(
        0.5, "nearest / second-nearest distance",
        "a predicted twin is taken as a vertex only if that vertex is the unambiguous nearest one (Lowe's "
        "ratio test): within the inner half of its neighbourhood, whatever the local sampling")
    robust_sigmas: float = _field(
        3.0, "robust standard deviations",
        "landing distances beyond this many robust standard deviations (1.4826 x median) are not twins: "
        "the usual outlier bound; on an exactly symmetric mesh it admits only exact twins")
    local_precision: float = _field(
        10.0, "x the neighbouring pairs' median misfit",
        "a vertex pair must fit the local mirror map of its neighbours nearly as well as they fit their own: "
        "misfits are heavy-tailed where the curvature changes, while a vertex without an exact twin among "
        "exact pairs misses by orders of magnitude")
    local_neighbours: int = _field(
        12, "pairs",
        "pairs fitting each local affine mirror map: the fewest that determine an affine map (4) with "
        "room for noise, few enough to stay local")
    vertex_twins: float = _field(
        1 / 3, "share of the twins found",
        "the mesh's vertices are taken to mirror each other when a third of the twins found are exact vertices "
        "at once (unambiguous, mutual, as precise as the map); where the two sides are sampled independently "
        "(a scan) only chance twins pass, about one in five at the most (on an outline the ratio test is first put "
        "on a surface's odds)")
    samples: int = _field(
        10_000, "vertices",
        "at most this many vertices, spread over the surface, are paired in each round: enough to choose "
        "the default auto_pair_count pairs from (one side of them), and the cost of a round stays bounded on "
        "million-vertex meshes")
    round_pairs: int = _field(
        1000, "pairs",
        "pairs of each round but the last: the rounds only have to find the twins, and the warp's cost grows "
        "with the cube of the pairs; the last solve takes auto_pair_count")
    registration_samples: int = _field(
        1000, "vertices",
        "points of the coherent point drift registration (its cost grows with their square)")
    registration_iterations: int = _field(
        100, "EM iterations",
        "most iterations of the registration's expectation-maximization; it stops earlier once the mixture's "
        "spread and the centres stop changing")
    least_gain: float = _field(
        0.05, "share of the output's mirror asymmetry",
        "a round that makes the output less than 5 % more mirror-symmetric than the round before is the "
        "last: the rounds converge geometrically, and the next would gain less still")
    converged_change: float = _field(
        1e-9, "x bounding-box diagonal",
        "the rounds stop when the output moves less than this: numerically the same output")

    @classmethod
    def describe(cls) -> str:
        """The fields as Markdown table rows: name, default, unit, reason."""
        rows = ["| field | default | unit | reason |", "|---|---|---|---|"]
        for field in dataclasses.fields(cls):
            rows.append(f"| `{field.name}` | {field.default!r} | {field.metadata['unit']} | {field.metadata['reason']} |")
        return "\n".join(rows)


DEFAULT = AutoConfig()
