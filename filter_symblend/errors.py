"""Errors and warnings raised by filter_symblend.

Every error is a ``ValueError`` subclass whose message names the problem and
the fix (which parameter, attribute, pair or vertex).
"""

from collections.abc import Sequence


def id_list(ids: Sequence, limit: int = 20) -> str:
    """``ids`` as "3, 8, 12", cut after ``limit`` with the total: "... (57 in all)"."""
    shown = ", ".join(str(i) for i in list(ids)[:limit])
    return shown + (f" ... ({len(ids)} in all)" if len(ids) > limit else "")


class SymblendError(ValueError):
    """Base class of every error filter_symblend raises for bad input."""


class ParameterError(SymblendError):
    """A filter parameter is unknown, of the wrong type or out of range."""


class MeshSetError(SymblendError):
    """The MeshSet has no mesh to work on."""


class LandmarkError(SymblendError):
    """The landmark pairs are missing, malformed or too few."""


class GeometryError(SymblendError):
    """The coordinates or the landmark layout make the problem degenerate."""


class DegenerateNeighbourhoodError(GeometryError):
    """The landmarks around some pairs lie (nearly) on a plane or a line, so the local transform the mode
    estimates is undetermined there; ``pair_ids`` are those pairs."""

    def __init__(self, message: str, pair_ids: Sequence):
        super().__init__(message)
        self.pair_ids = list(pair_ids)


class DisconnectedPairsError(GeometryError):
    """The pairs fall apart into groups at the width given; ``connecting_width`` (in the width's unit, the
    landmark spacing) is the least that connects them."""

    def __init__(self, message: str, connecting_width: float):
        super().__init__(message)
        self.connecting_width = connecting_width


class SymmetryNotFoundError(GeometryError):
    """Automatic pairs found no mirror symmetry to restore (the shape is not mirror-symmetric)."""


class SymblendWarning(UserWarning):
    """A soft problem: the filter ran, but a part of its input looks suspect."""
