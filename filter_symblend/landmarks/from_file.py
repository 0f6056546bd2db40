"""A landmark file on a mesh: read it, pair its landmarks (by name or by a pair table), trace its curves,
snap everything to vertices. What ``symblend symmetrize -l FILE`` does, for Python users."""

from __future__ import annotations

import dataclasses
import os

import numpy as np

from ..errors import LandmarkError
from .curves import add_curve_pairs, find_curves
from .formats import LandmarkSet, read_landmarks
from .geometric_pairing import MIN_LANDMARKS, pair_by_geometry
from .pairing import LEFT_WORDS, RIGHT_WORDS, SnappedPairs, pair_by_name, read_pair_table, snap_pairs


class AmbiguousPairingError(LandmarkError):
    """Landmarks paired by geometry, some ambiguously: ``problem`` names them, the message adds the fix;
    ``pair_names`` and ``midline_names`` hold what was paired confidently (to start a pair table from)."""

    FIX = "Give a pair table (--pair-table); `symblend landmarks check` writes the pairs found as one, to complete."

    def __init__(self, problem: str, pair_names: list[tuple[str, str]], midline_names: list[str]):
        super().__init__(f"{problem} {self.FIX}")
        self.problem, self.pair_names, self.midline_names = problem, pair_names, midline_names


def _geometric_pairs(points: np.ndarray, landmarks: LandmarkSet, singles: list[int], source: str):
    """(index pairs, midline indices) of the placed ``singles`` paired by geometry, the unplaced ones
    among the midline (where :func:`snap_pairs` lists them as left out); LandmarkError naming the ones
    that pair ambiguously."""
    placed = [i for i in singles if landmarks.landmarks[i].placed]
    names = landmarks.names()
    if len(placed) < MIN_LANDMARKS:
        raise LandmarkError(f"{source}: the landmark names carry no side (L_/R_ prefix or _left/_right suffix) "
                            f"and {len(placed)} placed landmarks are too few to pair by their mirror symmetry; "
                            "give a pair table (--pair-table).")
    positions = np.array([landmarks.landmarks[i].position for i in placed], dtype=float)
    found = pair_by_geometry(positions, points)
    if found.ambiguous:
        listed = ", ".join(repr(names[placed[i]]) for i in found.ambiguous[:20])
        raise AmbiguousPairingError(
            f"{source}: the names carry no side, and by geometry {len(found.ambiguous)} landmark(s) pair "
            f"ambiguously (their mirror image lands near two landmarks, or near none): {listed}.",
            [(names[placed[a]], names[placed[b]]) for a, b in found.pairs], [names[placed[i]] for i in found.midline])
    unplaced = [i for i in singles if not landmarks.landmarks[i].placed]
    return [(placed[a], placed[b]) for a, b in found.pairs], [placed[i] for i in found.midline] + unplaced


def pairs_from_landmark_file(points: np.ndarray, faces: np.ndarray | None, path: str | os.PathLike,
                             pair_table: str | os.PathLike | None = None,
                             side_words: tuple[tuple[str, ...], tuple[str, ...]] = (LEFT_WORDS, RIGHT_WORDS),
                             midline: bool = False, curves: bool = False, curve_spacing: float | None = None,
                             mesh_frame: str = "LPS", allow_far: bool = False,
                             specimen: str | int | None = None) -> SnappedPairs:
    """The landmark pairs of the file ``path`` on the mesh ``points`` (N, 3), ``faces`` (F, 3).

    Landmarks pair by name (``side_words``: prefixes or suffixes that mark each side, any case), by
    ``pair_table`` (a two-column CSV of names or 1-based numbers), or, when no name pairs and no table
    is given (numbered landmarks), by geometry (:mod:`.geometric_pairing`: mutual mirror partners, the
    landmarks on the mirror plane as the midline; ambiguous ones are an :class:`AmbiguousPairingError`
    naming them); with ``midline`` the unpaired ones are midline landmarks (else an error lists them);
    with ``curves`` numbered landmarks are curves, resampled about ``curve_spacing`` apart (mesh units; default 1 % of the diagonal). Coordinates in a
    file that states its frame (Slicer: LPS or RAS) are converted to ``mesh_frame``. Every landmark snaps
    to its nearest vertex; one farther than 2 % of the diagonal is an error unless ``allow_far``.
    ``specimen`` (ID or 1-based index) chooses one specimen of a .tps file.

    Returns the snapped pairs (``.pairs`` is the :class:`LandmarkPairs` for
    :func:`filter_symblend.symmetrize`; names, snap distances, curves and ``frame_note`` say what was
    done).
    """
    if curve_spacing and not curves:
        raise LandmarkError("`curve_spacing` spaces the semilandmarks of curves; set curves=True (--curves), or "
                            "leave it out.")
    source = str(path)
    landmarks, frame_note = read_landmarks(path, specimen).in_frame(mesh_frame)
    names = landmarks.names()
    found_curves, singles = find_curves(names, *side_words, midline) if curves else ([], range(len(names)))
    points = np.asarray(points, dtype=float)
    singles = list(singles)
    pairing = "pair table"
    if pair_table:
        index_pairs = read_pair_table(pair_table, names)
        paired = {i for pair in index_pairs for i in pair}
        unpaired = [i for i in singles if i not in paired]
    else:
        pairing = "names"
        index_pairs, unpaired = pair_by_name([names[i] for i in singles], *side_words)
        index_pairs = [(singles[a], singles[b]) for a, b in index_pairs]
        unpaired = [singles[i] for i in unpaired]
        if not index_pairs and unpaired:
            pairing = "geometry"
            index_pairs, unpaired = _geometric_pairs(points, landmarks, unpaired, source)
            midline = True
    faces = np.zeros((0, 3), dtype=np.int64) if faces is None else np.asarray(faces)
    snapped = snap_pairs(points, landmarks, index_pairs, unpaired, midline=midline, source=source,
                         allow_far=allow_far)
    snapped = add_curve_pairs(snapped, points, faces, landmarks, found_curves, spacing=curve_spacing, source=source,
                              allow_far=allow_far)
    return dataclasses.replace(snapped, frame_note=frame_note, pairing=pairing)
