"""From named landmarks to vertex pairs: pair by name or by a pair table, snap to vertices.

Name rule (default): a name pairs with another when they differ only by a side
word at the start or the end, any case, separated by "_", "-", "." or a space:
"L_orbitale" / "R_orbitale", "orbitale-left" / "Orbitale Right". A pair table
(Morpho's ``pairedLM``, geomorph's ``land.pairs``) is a two-column CSV of names
or 1-based landmark numbers, left column first.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import pathlib
import re
import warnings

import numpy as np
from scipy.spatial import cKDTree

from ..atomic import write_text
from ..core.geometry import bounding_diagonal
from ..core.landmark_pairs import LandmarkPairs
from ..errors import LandmarkError, SymblendWarning
from .formats import LandmarkFileError, LandmarkSet
from .text_files import csv_records, read_text

LEFT_WORDS = ("l", "left", "lt")
RIGHT_WORDS = ("r", "right", "rt")
FAR_FROM_SURFACE = 0.02  # snap distance, as a fraction of the bbox diagonal, that is reported
_SEPARATORS = re.compile(r"[_\-.\s]+")
NUMBERED = re.compile(r"[_\-.\s]+(\d+)\s*$")  # "L_zygomatic_arch_3", "OC-12": a curve's point number


def side_and_base(name: str, left_words=LEFT_WORDS, right_words=RIGHT_WORDS):
    """("left" | "right" | None, the name without its side word, lower case, "_"-joined)."""
    tokens = [t for t in _SEPARATORS.split(name.strip().lower()) if t]
    for side, words in (("left", left_words), ("right", right_words)):
        for position in (0, -1):
            if len(tokens) > 1 and tokens[position] in words:
                rest = tokens[1:] if position == 0 else tokens[:-1]
                return side, "_".join(rest)
    return None, "_".join(tokens)


def pair_by_name(names: list[str], left_words=LEFT_WORDS, right_words=RIGHT_WORDS):
    """Index pairs [(left, right)] by the name rule, and the indices of unpaired names."""
    sides: dict[str, dict[str, int]] = {"left": {}, "right": {}}
    unpaired = []
    for index, name in enumerate(names):
        side, base = side_and_base(name, left_words, right_words)
        if side is None:
            unpaired.append(index)
            continue
        if base in sides[side]:
            raise LandmarkError(f"Landmarks {names[sides[side][base]]!r} and {name!r} are both the {side} "
                                f"'{base}'; rename one.")
        sides[side][base] = index
    pairs = [(sides["left"][b], sides["right"][b]) for b in sides["left"] if b in sides["right"]]
    paired = {i for pair in pairs for i in pair}
    unpaired += [i for side in sides.values() for i in side.values() if i not in paired]
    return pairs, sorted(unpaired)


def read_pair_table(path, names: list[str]):
    """Index pairs [(left, right)] from a two-column CSV of landmark names or 1-based numbers."""
    path = pathlib.Path(path)
    rows = csv_records(read_text(path, "a pair table is a CSV of two columns, left and right"))
    lookup = {name: i for i, name in enumerate(names)}
    pairs = []
    for position, (number, row) in enumerate(rows):
        if len(row) < 2:
            raise LandmarkFileError(f"{path}, line {number}: expected two columns (left, right).")
        cells = [c.strip() for c in row[:2]]
        if all(c.isdigit() for c in cells):
            indices = [int(c) - 1 for c in cells]
            bad = [c for c, i in zip(cells, indices) if not 0 <= i < len(names)]
            if bad:
                raise LandmarkFileError(f"{path}, line {number}: landmark number {bad[0]} does not exist "
                                        f"(the landmark file has {len(names)}, numbered from 1).")
        elif all(c in lookup for c in cells):
            indices = [lookup[c] for c in cells]
        elif position == 0:
            continue  # a header row
        else:
            missing = next(c for c in cells if c not in lookup)
            raise LandmarkFileError(f"{path}, line {number}: no landmark is named {missing!r}.")
        pairs.append(tuple(indices))
    return pairs


def write_pair_table(path, pair_names: list[tuple[str, str]], midline_names: list[str]) -> None:
    """Write ``pair_names`` as a pair table that :func:`read_pair_table` reads (a header, then one
    ``left,right`` row per pair); the midline landmarks are named in the header's comment column."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["left", "right", f"midline (use --midline): {' '.join(midline_names) or 'none'}"])
    writer.writerows(pair_names)
    write_text(path, out.getvalue())


def nearest_vertices(points: np.ndarray, positions: np.ndarray, names: list[str], source: str,
                     allow_far: bool = False):
    """Distances and indices (k,) of the vertices of ``points`` (N, 3) nearest to ``positions``
    (k, 3). Points farther than FAR_FROM_SURFACE from the surface are an error that names them
    (a wrong coordinate system or unit is likelier than such a landmark), a warning with ``allow_far``."""
    distances, vertices = cKDTree(points).query(positions)
    diagonal = bounding_diagonal(points)
    far = np.flatnonzero(distances > FAR_FROM_SURFACE * diagonal)
    if far.size:
        shown = ", ".join(f"{names[i]} ({distances[i]:.3g})" for i in far[:10])
        message = (f"{source}: {shown} lie far from the mesh surface (more than {FAR_FROM_SURFACE:.0%} of the "
                   "diagonal); check the file's coordinate system (--mesh-frame) and units")
        if not allow_far:
            raise LandmarkError(f"{message}, or snap them anyway with --allow-far-landmarks (allow_far=True).")
        warnings.warn(f"{message}.", SymblendWarning, stacklevel=3)
    return distances, vertices


@dataclasses.dataclass
class SnappedPairs:
    """Landmark pairs (and midline landmarks) on mesh vertices, with what was done to get there."""

    pairs: LandmarkPairs
    pair_names: list[tuple[str, str]]
    midline_names: list[str]
    snap_distances: np.ndarray  # (n, 2) for the pairs, mesh units
    unplaced: list[str]
    curves: list[dict] = dataclasses.field(default_factory=list)  # what each curve became (curves.py)
    placed_spacing: float | None = None  # with curves: mean nearest spacing of the placed points
    frame_note: str = ""  # how the file's coordinates were converted to the mesh's frame
    pairing: str = "names"  # how the landmarks were paired: "names", "pair table" or "geometry"

    def weights(self, missing: list[str]):
        """(left, right) weights (n,): 0 for the landmarks named in ``missing``, 1 elsewhere."""
        known = {name for pair in self.pair_names for name in pair}
        unknown = [name for name in missing if name not in known]
        if unknown:
            raise LandmarkError(f"--missing names {', '.join(map(repr, unknown))}, which no pair has; "
                                f"pair landmarks are: {', '.join(sorted(known)[:20])}.")
        return tuple(np.array([0.0 if pair[side] in missing else 1.0 for pair in self.pair_names])
                     for side in (0, 1))


def snap_pairs(points: np.ndarray, landmarks: LandmarkSet, index_pairs, unpaired: list[int],
               midline: bool = False, source: str = "landmarks", allow_far: bool = False) -> SnappedPairs:
    """Snap every placed landmark to its nearest vertex of ``points`` (N, 3) (far from the surface: an
    error unless ``allow_far``, see :func:`nearest_vertices`).

    Pairs with an unplaced side are left out (and listed). Unpaired landmarks are
    midline landmarks when ``midline`` is true, an error that lists them otherwise.
    Two landmarks on one vertex are an error naming both.
    """
    names = landmarks.names()
    if unpaired and not midline:
        listed = ", ".join(repr(names[i]) for i in unpaired[:20])
        numbered = [names[i] for i in unpaired if NUMBERED.search(names[i])]
        hint = f" If {numbered[0]!r} is a point of a curve, pass --curves." if numbered else ""
        raise LandmarkError(
            f"{source}: {len(unpaired)} landmark(s) have no partner: {listed}. Name them with a side "
            "(L_/R_ prefix or _left/_right suffix), list them in a pair table (--pair-table), or declare "
            f"them midline landmarks (--midline).{hint}")
    placed = [(a, b) for a, b in index_pairs if landmarks.landmarks[a].placed and landmarks.landmarks[b].placed]
    unplaced = [f"{names[a]}/{names[b]}" for a, b in index_pairs if (a, b) not in placed]
    unplaced += [names[i] for i in unpaired if not landmarks.landmarks[i].placed]
    on_plane = [i for i in unpaired if landmarks.landmarks[i].placed]
    if unplaced:
        warnings.warn(f"{source}: {', '.join(unplaced)} have a landmark marked as not placed and "
                      "are left out.", SymblendWarning, stacklevel=2)
    order = [i for pair in placed for i in pair] + on_plane
    positions = np.array([landmarks.landmarks[i].position for i in order], dtype=float).reshape(-1, 3)
    distances, vertices = nearest_vertices(points, positions, [names[i] for i in order], source, allow_far)
    sorted_at = np.argsort(vertices, kind="stable")
    same = np.flatnonzero(np.diff(vertices[sorted_at]) == 0)
    if same.size:
        a, b = sorted_at[same[0]], sorted_at[same[0] + 1]
        raise LandmarkError(f"{source}: landmarks {names[order[a]]!r} and {names[order[b]]!r} both snap to "
                            f"vertex {vertices[a]}; move one of them, or use a finer mesh.")
    count = 2 * len(placed)
    pair_vertices = vertices[:count].reshape(-1, 2)
    pairs = LandmarkPairs(np.arange(1, len(placed) + 1), pair_vertices[:, 0], pair_vertices[:, 1],
                          vertices[count:])
    return SnappedPairs(pairs, [(names[a], names[b]) for a, b in placed], [names[i] for i in on_plane],
                        distances[:count].reshape(-1, 2), unplaced)
