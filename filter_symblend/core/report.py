"""The report of a symmetrization, typed: what the solve measured (the mirror plane, the landmarks' asymmetry,
the widths, the local fits, the timings) and the parts the layers above add (the uncertainty, the missing
region, the automatic pairs, the before/after checks, warnings).

Every layer reads these attributes; :meth:`Report.to_dict` is the one JSON form: the MeshSet filter's return
value, the command's ``--report`` file, and what ``symblend batch``'s table reads (the report table of
docs/method.md lists its keys). A part another layer fills (``auto_pairs``, ``checks``) needs only its
``warnings`` and ``to_dict()``.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Protocol

import numpy as np

from .geometry import MirrorPlane


class ReportPart(Protocol):
    """A part of the report a layer above fills: the warnings it raised, and its JSON form."""

    warnings: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]: ...


@dataclasses.dataclass(frozen=True)
class Spread:
    """How far the vertices moved, mesh units: ``mean``, ``rms`` and ``max`` of the distances."""

    mean: float
    rms: float
    max: float

    @classmethod
    def of(cls, distances: np.ndarray) -> Spread:
        """The spread of ``distances`` (N,) >= 0."""
        return cls(float(distances.mean()), float(np.sqrt(np.mean(distances**2))), float(distances.max()))

    def to_dict(self) -> dict[str, float]:
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class LandmarkAsymmetry:
    """How far the landmark pairs are from mirror images across their best plane: ``rms`` and ``max`` of
    each pair's deviation (mesh units) and the bounding-box ``diagonal`` they are relative to."""

    rms: float
    max: float
    diagonal: float

    @property
    def rms_relative(self) -> float:
        return self.rms / self.diagonal

    @property
    def max_relative(self) -> float:
        return self.max / self.diagonal

    def to_dict(self) -> dict[str, float]:
        return {"rms": self.rms, "max": self.max, "rms_relative": self.rms_relative,
                "max_relative": self.max_relative}


@dataclasses.dataclass(frozen=True)
class Widths:
    """The neighbourhood widths used (the README's parameters): the landmarks' ``mean_landmark_spacing`` measured,
    the ``width_spacing`` the widths are multiples of, ``phi_width`` and ``theta_width`` (in spacings)
    and ``phi_h``, ``theta_h`` (mesh units), and ``alpha``."""

    mean_landmark_spacing: float
    width_spacing: float
    phi_width: float
    phi_h: float
    theta_width: float
    theta_h: float
    alpha: float


@dataclasses.dataclass(frozen=True)
class LocalFit:
    """Step 1's local symmetries: the median and max of their residuals, the least and most stretch."""

    residual_median: float
    residual_max: float
    stretch_min: float
    stretch_max: float


@dataclasses.dataclass(frozen=True)
class Timings:
    """Seconds: each of the solve's ``stages`` (name -> seconds, in order), their ``total`` (with automatic
    pairs: every round), the MeshSet filter's ``checks`` (each measurement's own seconds; they overlap the
    solve) and the whole ``filter`` call (None outside the filter)."""

    stages: dict[str, float]
    total: float
    checks: dict[str, float] | None = None
    filter: float | None = None

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {**self.stages, "total": self.total}
        if self.checks is not None:
            out["checks"] = dict(self.checks)
        if self.filter is not None:
            out["filter"] = self.filter
        return out


@dataclasses.dataclass(frozen=True)
class UncertaintySummary:
    """How sure the restoration is (core/uncertainty, core/placement), relative to the diagonal: the
    per-vertex spread's ``median``, ``p90`` and ``max`` (``method`` 'jackknife': its standard error;
    'placement': the RMS change that landmarks placed with RMS error ``landmark_precision``, mesh units, cause);
    each left-out unit's ``influence`` (label -> how far the result moves without it, or without its group:
    beyond 100 units they are left out in ``groups`` random groups), the
    ``most_influential_pair``, the units ``kept_in`` (label -> why they cannot be left out); each unit's
    ``mirror_error`` (label -> how far from mirroring the restoration by the others leaves it), the unit
    that is ``probably_misplaced`` (or None) and the ``warnings`` that say so."""

    left_out: int
    median_relative: float
    p90_relative: float
    max_relative: float
    influence_relative: dict[str, float]
    most_influential_pair: str
    kept_in: dict[str, str]
    mirror_error_relative: dict[str, float]
    probably_misplaced: str | None = None
    warnings: tuple[str, ...] = ()
    method: str = "jackknife"
    landmark_precision: float | None = None
    groups: int | None = None

    def to_dict(self) -> dict[str, Any]:
        return {**dataclasses.asdict(self), "warnings": list(self.warnings)}


@dataclasses.dataclass(frozen=True)
class MirrorMapReport:
    """How sure a mirror map is (core/mirror_pairs): its ``map`` name; the share of the pairable vertices
    with a twin the map supports (``coverage``: it lands on the surface facing the mirrored way; other twins are
    listed with confidence 0), of the landings that are supported twins (``consistency``) and with a confident
    twin (``confident_share``, confidence >= ``confidence_threshold``); the median of each error in local
    spacings over the supported twins (``round_trip``, ``landing``, ``neighbours``; None without any);
    other symmetries that mirror about as much of the surface and lowered the confidence where they disagree
    (``alternatives``: name -> share, auto/rivals)."""

    map: str
    coverage: float
    consistency: float
    confident_share: float
    confidence_threshold: float
    median_errors_in_spacings: dict[str, float | None]
    alternatives: dict[str, float] = dataclasses.field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True, eq=False)
class Report:
    """What a symmetrization measured. ``pair_count`` and ``midline_count``: the landmark pairs and midline
    landmarks given (automatic pairs are counted in ``auto_pairs``); ``plane``: the mirror plane of the
    output, in its frame; ``canonical_from_input`` (4, 4): the rigid map from the input frame to the
    canonical one (plane x = 0); ``landmark_asymmetry_before``/``_after`` (None without landmark pairs);
    ``vertex_displacement``: how far the vertices moved, input frame; ``diagonal``: the input's
    bounding-box diagonal; ``warp``: how the spline was solved. Filled by the layers above when they apply:
    ``filled_vertices`` (a missing region), ``uncertainty``, ``auto_pairs`` (auto/report) and ``checks``
    (the MeshSet filter's before/after figures, measures/checks); :attr:`warnings` gathers theirs."""

    pair_count: int
    midline_count: int
    mode: str
    output_frame: str
    plane: MirrorPlane
    canonical_from_input: np.ndarray
    landmark_asymmetry_before: LandmarkAsymmetry | None
    landmark_asymmetry_after: LandmarkAsymmetry | None
    vertex_displacement: Spread
    diagonal: float
    widths: Widths
    local_fit: LocalFit
    warp: str
    seconds: Timings
    filled_vertices: int | None = None
    uncertainty: UncertaintySummary | None = None
    auto_pairs: ReportPart | None = None
    checks: ReportPart | None = None

    @property
    def warnings(self) -> tuple[str, ...]:
        """The warnings of the automatic pairs, of the uncertainty and of the checks, in that order."""
        return tuple(message for part in (self.auto_pairs, self.uncertainty, self.checks) if part is not None
                     for message in part.warnings)

    def replace(self, **changes) -> Report:
        """A copy with ``changes`` (field name -> value)."""
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        """The JSON form: flat keys, as the report table of docs/method.md lists them; the parts that do not
        apply are left out."""
        widths, fit = self.widths, self.local_fit
        out: dict[str, Any] = {
            "pair_count": self.pair_count,
            "midline_count": self.midline_count,
            "mode": self.mode,
            "output_frame": self.output_frame,
            "plane_normal": [float(value) for value in self.plane.normal],
            "plane_offset": float(self.plane.offset),
            "canonical_from_input": np.asarray(self.canonical_from_input, dtype=float).tolist(),
        }
        if self.landmark_asymmetry_before is not None:
            out["landmark_asymmetry_before"] = self.landmark_asymmetry_before.to_dict()
            out["landmark_asymmetry_after"] = self.landmark_asymmetry_after.to_dict()
        out.update({
            "vertex_displacement": self.vertex_displacement.to_dict(),
            "diagonal": self.diagonal,
            **dataclasses.asdict(widths),
            "local_fit_residual": {"median": fit.residual_median, "max": fit.residual_max},
            "local_stretch": {"min": fit.stretch_min, "max": fit.stretch_max},
            "warp": self.warp,
            "seconds": self.seconds.to_dict(),
        })
        if self.filled_vertices is not None:
            out["filled_vertices"] = self.filled_vertices
        if self.uncertainty is not None:
            out["uncertainty"] = self.uncertainty.to_dict()
        if self.auto_pairs is not None:
            out["auto_pairs"] = self.auto_pairs.to_dict()
        if self.checks is not None:
            out.update(self.checks.to_dict())
        return out
