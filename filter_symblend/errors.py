"""Errors and warnings raised by filter_symblend.

Every error is a ``ValueError`` subclass whose message names the problem and
the fix (which parameter, attribute, pair or vertex).
"""


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


class SymblendWarning(UserWarning):
    """A soft problem: the filter ran, but a part of its input looks suspect."""
