"""What the automatic pairs report, typed: each round's pair search and solve, why the rounds stopped, and
the mirror map the result carries. ``to_dict()`` gives the JSON form under the report's ``auto_pairs``
(docs/automatic-pairs.md lists its keys)."""

from __future__ import annotations

import dataclasses
from typing import Any

from ..core.geometry import MirrorPlane
from ..core.report import MirrorMapReport


def _without_none(record: dict[str, Any]) -> dict[str, Any]:
    return {key: value for key, value in record.items() if value is not None}


@dataclasses.dataclass(frozen=True)
class PairSearch:
    """One search for pairs under a mirror map (auto/pairs): the ``map``'s name, the share of the sample
    with a ``twins`` on the surface, its ``consistency`` (twins / landings), the share of ``vertex_twins``,
    what the twins are (``twins_are``: "exact vertices" or "points of the surface") and how many
    ``candidates`` the pairs were spread from. Exact vertex pairs add how the growth went (``growth_waves``,
    ``dropped``), whether the tessellation is mirrored (``tessellation_mirror``, meshes only) and the
    ``vertex_share`` of the usable vertices paired."""

    map: str
    twins: float
    consistency: float
    vertex_twins: float
    twins_are: str | None = None
    candidates: int | None = None
    growth_waves: int | None = None
    dropped: int | None = None
    tessellation_mirror: bool | None = None
    vertex_share: float | None = None

    @property
    def share_paired(self) -> float:
        """The share of the surface the search paired: the vertex share for exact pairs, else the twins'."""
        return self.twins if self.vertex_share is None else self.vertex_share

    def to_dict(self) -> dict[str, Any]:
        return _without_none(dataclasses.asdict(self))


_START_KEYS = {"landmarks": "landmarks_only", "intrinsic": "intrinsic_start"}


@dataclasses.dataclass(frozen=True)
class Round:
    """One solve of the rounds: its output's ``surface_asymmetry`` (RMS distance to its own reflection /
    diagonal). A start records only that and where it came from (``start``: "landmarks" or "intrinsic");
    a round adds its pair ``search``, the automatic ``pairs`` and ``midline`` vertices it used, the largest
    ``change`` of a vertex from the output before (/ diagonal), whether it was ``kept`` (a round that left
    the output less symmetric is not), whether it is the ``final`` solve with every pair, the widths
    it had to raise (``raised_widths``: name -> value), and how many of its pairs it ``carried`` over from the
    solve before, where its own search did not reach (:func:`.pairs.keeping_unreached`)."""

    surface_asymmetry: float
    start: str | None = None
    search: PairSearch | None = None
    pairs: int | None = None
    midline: int | None = None
    change: float | None = None
    kept: bool = True
    final: bool = False
    raised_widths: dict[str, float] = dataclasses.field(default_factory=dict)
    carried: int = 0

    @property
    def is_start(self) -> bool:
        return self.start is not None

    def to_dict(self) -> dict[str, Any]:
        if self.is_start:
            return {_START_KEYS[self.start]: True, "surface_asymmetry": self.surface_asymmetry}
        out = {**self.search.to_dict(), "pairs": self.pairs, "midline": self.midline,
               "surface_asymmetry": self.surface_asymmetry, **self.raised_widths}
        if self.change is not None:
            out["change"] = self.change
        if self.carried:
            out["carried"] = self.carried
        if not self.kept:
            out["kept"] = False
        if self.final:
            out["final"] = True
        return out


@dataclasses.dataclass(frozen=True, eq=False)
class AutomaticPairsReport:
    """The automatic pairs of a result: the ``pair_count`` and ``midline_count`` they added, the ``rounds``
    in order, why they ``stopped``, what the kept pairs' twins are (``twins_are``) and their map's
    ``consistency``, the ``mirror_map`` the result carries, the ``excluded_vertices`` count, the share each
    first map mirrored (``coverage``: name -> share) and the input's ``surface_plane`` (both None when
    landmarks or the intrinsic mirror started the rounds), what the intrinsic start tried
    (``intrinsic_start``, a diagnostic record; None unless it ran), the output's distance to its own
    reflection over the scored vertices (``output_asymmetry``: RMS, ``output_asymmetry_p99``: 99th
    percentile; / diagonal) and the ``warnings`` raised."""

    pair_count: int
    midline_count: int
    rounds: tuple[Round, ...]
    stopped: str
    twins_are: str | None
    consistency: float | None
    mirror_map: MirrorMapReport
    excluded_vertices: int
    coverage: dict[str, float] | None = None
    surface_plane: MirrorPlane | None = None
    intrinsic_start: dict[str, Any] | None = None
    output_asymmetry: float | None = None
    output_asymmetry_p99: float | None = None
    warnings: tuple[str, ...] = ()

    @property
    def alternatives(self) -> dict[str, float]:
        """The other symmetries that mirror about as much of the surface as the first map (name -> share,
        :mod:`.rivals`): its mirror map's, whose confidence they lowered."""
        return self.mirror_map.alternatives

    def to_dict(self) -> dict[str, Any]:
        out = {"excluded_vertices": self.excluded_vertices}
        if self.coverage is not None:
            out["coverage"] = dict(self.coverage)
            out["surface_plane"] = {"normal": [float(value) for value in self.surface_plane.normal],
                                   "offset": float(self.surface_plane.offset)}
        if self.intrinsic_start is not None:
            out["intrinsic_start"] = self.intrinsic_start
        out["rounds"] = [entry.to_dict() for entry in self.rounds]
        if self.warnings:
            out["warnings"] = list(self.warnings)
        out.update(stopped=self.stopped, pair_count=self.pair_count, midline_count=self.midline_count,
                   twins_are=self.twins_are, consistency=self.consistency, mirror_map=self.mirror_map.to_dict(),
                   output_asymmetry=self.output_asymmetry, output_asymmetry_p99=self.output_asymmetry_p99)
        return out
