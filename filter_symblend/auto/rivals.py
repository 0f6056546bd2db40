"""Other mirror symmetries that fit a shape about as well as the chosen one: a box's three planes, the planes
through the axis of a body of revolution, two ways to mirror a posed body.

A candidate map is a *rival* of the chosen one when it is a different symmetry, sending the surface elsewhere
(the median distance between the two maps' twins over the scored vertices exceeds the landing tolerance; two
registrations of one symmetry agree within it), and when it mirrors about as much of the surface, within
``field_precision`` of the landing tolerance: the chosen map's share there exceeds its share by no more than
two standard errors of the difference on the scored vertices (McNemar's: ``2 sqrt(b + c) / m``, with b and c
the vertices only one of the two mirrors). Within the whole tolerance a plane turned a few degrees about the
axis of a body of revolution still mirrors nearly all of it, parts included; within a quarter of it, only the
planes that mirror the parts do (the planes of a box, of a plain cylinder, stay exact). A candidate plane is
refined first as the best plane was (reflection ICP on the large sample: the others are left coarse). Rivals
that are one symmetry between them are named once. The automatic pairs name the rivals in the report and a
warning, and each twin's confidence is lowered by how far a rival puts it (:func:`rival_agreement`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..core.mirror_planes import best_plane_from
from .config import AutoConfig
from .maps import MirrorMap, plane_map
from .twins import covered_by

SIGNIFICANCE = 2.0  # standard errors: a share further below the chosen one's is not "about as well"


@dataclasses.dataclass(frozen=True)
class Rival:
    """A different mirror symmetry (``mirror``) that mirrors ``share`` of the surface."""

    mirror: MirrorMap
    share: float


def _mirrored(mirror: MirrorMap, scored: np.ndarray, config: AutoConfig) -> np.ndarray:
    """(m,) bool: the ``scored`` vertices ``mirror`` mirrors within ``field_precision`` of the landing tolerance."""
    tolerance = config.field_precision * config.landing_tolerance * mirror.surface.diagonal
    return covered_by(mirror, scored, tolerance)


def close_rivals(best: MirrorMap, candidates: list[MirrorMap], shares: dict[str, float], scored: np.ndarray,
                 config: AutoConfig) -> list[Rival]:
    """The ``candidates`` that are rivals of ``best`` (see the module doc), by share; ``shares``: name -> share
    of the ``scored`` (m,) vertices each mirrors."""
    surface = best.surface
    # Only candidates whose share within the whole tolerance is this close are tested (the test allows at most
    # this difference, b + c <= m): the rest cost nothing.
    bound = SIGNIFICANCE / np.sqrt(len(scored))
    near = [mirror for mirror in candidates
            if mirror.name != best.name and shares[mirror.name] >= shares[best.name] - bound]
    if not near:
        return []
    tolerance = config.landing_tolerance * surface.diagonal
    positions = surface.points[scored]
    mirrored = _mirrored(best, scored, config)
    named = [best.predict(positions)]
    rivals = []
    for mirror in sorted(near, key=lambda candidate: -shares[candidate.name]):
        if mirror.plane is not None:  # refined as the best plane was: a coarse fit would lose the precise test
            refined = best_plane_from(surface.points[surface.usable_index], [mirror.plane])
            mirror = plane_map(surface, *refined, name=mirror.name)
        other = _mirrored(mirror, scored, config)
        gain = np.count_nonzero(mirrored & ~other) - np.count_nonzero(other & ~mirrored)
        if gain > SIGNIFICANCE * np.sqrt(np.count_nonzero(other != mirrored)):
            continue
        twins = mirror.predict(positions)
        if any(np.median(np.linalg.norm(twins - earlier, axis=1)) <= tolerance for earlier in named):
            continue  # a symmetry already named
        named.append(twins)
        rivals.append(Rival(mirror, shares[mirror.name]))
    return rivals


def rival_agreement(rivals: list[Rival], positions: np.ndarray, twins: np.ndarray, spacing: np.ndarray) -> np.ndarray:
    """(k,) in (0, 1]: ``exp(-d^2 / 2)``, d the distance from each twin (k, 3) of the vertices at ``positions``
    (k, 3) to where the farthest rival puts it, in units of the local ``spacing`` (k,); 1 without rivals (the
    same length and form as the map's own evidence, :mod:`.confidence`)."""
    agreement = np.ones(len(positions))
    for rival in rivals:
        distance = np.linalg.norm(rival.mirror.predict(positions) - twins, axis=1) / spacing
        agreement = np.minimum(agreement, np.exp(-0.5 * distance**2))
    return agreement


def rival_warning(best: str, share: float, rivals: list[Rival]) -> str:
    """The warning a result deserves when other symmetries fit about as well as its map ``best``."""
    listed = ", ".join(f"{rival.mirror.name} ({rival.share:.0%})" for rival in rivals)
    return (f"another mirror symmetry fits this shape about as well as the one paired ({best}, {share:.0%} of the "
            f"surface mirrored): {listed} (a box, a body of revolution). The pairs follow {best}, and their "
            "confidence is low where the others disagree. If you mean another, place a few landmark pairs across it "
            "(pairs='landmarks+auto').")
