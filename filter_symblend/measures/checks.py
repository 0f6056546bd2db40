"""The before/after checks of a run as a part of its report (core/report): the input's and the output's
mirror asymmetry, the two-way distance between them, and what they say (measures/verdict)."""

from __future__ import annotations

import dataclasses
from typing import Any

from .verdict import result_warnings


@dataclasses.dataclass(frozen=True)
class Checks:
    """The figures of measures/surface_asymmetry: ``before`` (the input's mirror asymmetry) and ``after``
    (the output's), ``hausdorff`` (measures/hausdorff, input <-> output;
    None unless ``checks='full'``); ``nothing_to_restore``: the input was given back, and ``symmetrized``
    is then what the output would have measured; the ``warnings`` they deserve (measures/verdict)."""

    before: dict[str, Any]
    after: dict[str, Any]
    hausdorff: dict[str, float] | None = None
    nothing_to_restore: bool = False
    symmetrized: dict[str, Any] | None = None
    warnings: tuple[str, ...] = ()

    @classmethod
    def measured(cls, figures: dict[str, dict], report, automatic: bool, unchanged: bool) -> Checks:
        """The part of the finished checks' ``figures`` ("before", "after", perhaps "hausdorff") of a run whose
        ``report`` (core/report.Report) gives the diagonal and the landmark pair count, with their warnings;
        ``automatic``: dense automatic pairs were added; ``unchanged``: the input was given back, so the
        output's figures are the input's."""
        before, after, hausdorff = figures["before"], figures["after"], figures.get("hausdorff")
        messages = tuple(result_warnings(before, after, hausdorff, report.diagonal, report.pair_count, automatic,
                                         unchanged))
        if unchanged:
            return cls(before, before, None if hausdorff is None else dict.fromkeys(hausdorff, 0.0), True, after,
                       messages)
        return cls(before, after, hausdorff, warnings=messages)

    def to_dict(self) -> dict[str, Any]:
        """The report's keys: ``mirror_asymmetry_before``/``_after``, ``hausdorff_input_output``, and
        ``nothing_to_restore`` with ``symmetrized_asymmetry`` when the input was given back."""
        out: dict[str, Any] = {"mirror_asymmetry_before": self.before, "mirror_asymmetry_after": self.after}
        if self.hausdorff is not None:
            out["hausdorff_input_output"] = self.hausdorff
        if self.nothing_to_restore:
            out.update(nothing_to_restore=True, symmetrized_asymmetry=self.symmetrized)
        out["warnings"] = list(self.warnings)
        return out
