"""Named 3D points as landmark files hold them, and the rules every format shares: what marks a coordinate
missing, how a bad number is reported, and how one of several sets in a file is chosen."""

from __future__ import annotations

import dataclasses
import math
import warnings

from ..errors import SymblendError, SymblendWarning

MISSING_WORDS = {"na", "nan", "-999", "-999.0", "9999", "9999.0"}  # a missing coordinate, as the field writes it


class LandmarkFileError(SymblendError):
    """A landmark file cannot be read: it names the file, the line or point, and the fix."""


@dataclasses.dataclass
class Landmark:
    """A named point; ``placed`` is False where the file marks it as not placed."""

    name: str
    position: tuple[float, float, float]
    placed: bool = True


@dataclasses.dataclass
class LandmarkSet:
    landmarks: list[Landmark]
    coordinate_system: str | None = None

    def names(self) -> list[str]:
        return [lm.name for lm in self.landmarks]

    def in_frame(self, frame: str | None) -> tuple["LandmarkSet", str]:
        """A copy in ``frame`` ("LPS", "RAS" or None = as stored) and a sentence saying what was done."""
        if frame is None or self.coordinate_system is None or frame == self.coordinate_system:
            return self, "coordinates used as stored"
        flipped = [dataclasses.replace(lm, position=(-lm.position[0], -lm.position[1], lm.position[2]))
                   for lm in self.landmarks]
        return (LandmarkSet(flipped, frame),
                f"coordinates converted from {self.coordinate_system} to {frame} (x and y negated)")


def is_missing(text) -> bool:
    """Whether a coordinate's text marks a missing landmark (NA, NaN, -999, 9999)."""
    return text is not None and str(text).strip().lower() in MISSING_WORDS


def position_of(texts, where: str) -> tuple[tuple[float, float, float], bool]:
    """(x, y, z) and whether the landmark is placed, from three coordinate texts (missing: zeros, False)."""
    if any(is_missing(t) for t in texts):
        return (0.0, 0.0, 0.0), False
    return tuple(parse_number(t, where) for t in texts), True


def parse_number(text: str, where: str) -> float:
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise LandmarkFileError(f"{where}: {text!r} is not a number.") from None
    if not math.isfinite(value):
        raise LandmarkFileError(f"{where}: coordinate {text!r} is not finite.")
    return value


def chosen_index(identifiers: list[str | None], shown: list[str], path: str, specimen: str | int | None,
            what: str = "specimens") -> int:
    """The index of the one of ``what`` (a file's specimens, or markups) that ``specimen`` names: an
    identifier, else a 1-based index; the first, with a warning naming the others, when None."""
    if specimen is None:
        if len(identifiers) > 1:
            warnings.warn(f"{path} holds {len(identifiers)} {what} ({', '.join(shown[:10])}"
                          f"{', ...' if len(shown) > 10 else ''}); the first ({shown[0]}) is used. Choose one with "
                          "--specimen ID or INDEX.", SymblendWarning, stacklevel=4)
        return 0
    text = str(specimen).strip()
    if text in identifiers:
        return identifiers.index(text)
    if text.isdigit() and 1 <= int(text) <= len(identifiers):
        return int(text) - 1
    raise LandmarkFileError(f"{path}: no {what[:-1]} {text!r}; its {what} are {', '.join(shown[:20])} "
                            f"(by {'name' if what == 'markups' else 'ID'}, or by index 1..{len(identifiers)}).")
