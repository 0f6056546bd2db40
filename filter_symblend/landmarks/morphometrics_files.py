"""The geometric morphometrics programs' study files (geomorph, Morpho, MorphoJ): Rohlf's TPS (LM3= blocks,
ID=, SCALE=) and NTSYS matrices (.nts), each holding several specimens, one chosen by ID or index."""

from __future__ import annotations

import dataclasses

from ..atomic import write_text
from .landmark_set import Landmark, LandmarkFileError, LandmarkSet, chosen_index, parse_number, position_of
from .text_files import lines as text_lines


@dataclasses.dataclass
class _Specimen:
    rows: list[list[str]]  # coordinate texts per landmark
    line: int  # line of its LM3= line
    identifier: str | None = None
    scale: float = 1.0


def _tps_specimens(text: str, path: str) -> list[_Specimen]:
    """The specimens of a TPS file, in order; 2D files (LM=) are refused."""
    specimens, lines, number = [], text_lines(text), 0
    while number < len(lines):
        line = lines[number].strip()
        number += 1
        key, _, value = line.partition("=")
        key = key.strip().upper()
        if key == "LM":
            raise LandmarkFileError(f"{path}, line {number}: LM= holds 2D landmarks; the filter needs 3D ones "
                                    "(LM3=). Digitize them on the 3D mesh, or export LM3 from your software.")
        if key == "LM3":
            try:
                count = int(value)
            except ValueError:
                raise LandmarkFileError(f"{path}, line {number}: LM3={value.strip()!r} is not a count.") from None
            rows = [lines[i].split() for i in range(number, number + count) if i < len(lines)]
            if len(rows) < count or any(len(row) != 3 for row in rows):
                bad = next((i for i, row in enumerate(rows) if len(row) != 3), len(rows))
                raise LandmarkFileError(f"{path}, line {number + bad + 1}: LM3={count} needs {count} lines of x y z "
                                        f"(landmark {bad + 1} has {len(rows[bad]) if bad < len(rows) else 'no'} "
                                        "values).")
            specimens.append(_Specimen(rows, number))
            number += count
        elif key == "POINTS":  # the points of a curve (2D outlines): skipped
            number += int(value)
        elif key == "ID" and specimens:
            specimens[-1].identifier = value.strip()
        elif key == "SCALE" and specimens:
            scale = parse_number(value, f"{path}, line {number} (SCALE)")
            if scale <= 0:
                raise LandmarkFileError(f"{path}, line {number}: SCALE={value.strip()} must be positive.")
            specimens[-1].scale = scale
    return specimens


def _chosen_specimen(specimens: list[_Specimen], path: str, specimen: str | int | None) -> _Specimen:
    if not specimens:
        raise LandmarkFileError(f"{path}: no LM3= block; a TPS file of 3D landmarks starts each specimen with "
                                "LM3=<count>.")
    identifiers = [s.identifier for s in specimens]
    shown = [s.identifier or str(i) for i, s in enumerate(specimens, start=1)]
    return specimens[chosen_index(identifiers, shown, path, specimen)]


def _specimen_landmarks(chosen: _Specimen, where) -> LandmarkSet:
    """A specimen's landmarks, named 1..k, its scale applied; ``where(k)`` names landmark k's place in
    messages."""
    landmarks = []
    for index, row in enumerate(chosen.rows, start=1):
        position, placed = position_of(row, where(index))
        landmarks.append(Landmark(str(index), tuple(chosen.scale * v for v in position), placed))
    return LandmarkSet(landmarks)


def read_tps(text: str, path: str, specimen: str | int | None = None) -> LandmarkSet:
    """One specimen of a TPS file (see the module docstring): landmarks named 1..k, SCALE applied."""
    chosen = _chosen_specimen(_tps_specimens(text, path), path, specimen)
    return _specimen_landmarks(chosen, lambda index: f"{path}, line {chosen.line + index}")


def write_tps(landmarks: LandmarkSet, identifier: str = "specimen") -> str:
    rows = [" ".join(repr(float(v)) for v in lm.position) if lm.placed else "NA NA NA" for lm in landmarks.landmarks]
    return f"LM3={len(rows)}\n" + "".join(row + "\n" for row in rows) + f"ID={identifier}\n"


def write_tps_study(path, specimens: dict[str, LandmarkSet]) -> None:
    """Several specimens (ID -> landmarks) in one TPS file, as geomorph's readland.tps and Morpho's
    readallTPS read them (missing coordinates as NA)."""
    write_text(path, "".join(write_tps(landmarks, identifier) for identifier, landmarks in specimens.items()))


def _nts_specimens(text: str, path: str) -> list[_Specimen]:
    """The specimens of an NTS file in the multiple-specimen format (Rohlf): a parameter line
    ``1 n[L] p*k[L] 0|1 [missing code] DIM=3``, then the labels (if L), then n rows of p*k values; text
    after a double quote is a comment."""
    tokens = []
    for number, line in enumerate(text_lines(text), start=1):
        tokens += [(token, number) for token in line.split('"')[0].split()]
    if len(tokens) < 4 or tokens[0][0] != "1":
        raise LandmarkFileError(f"{path}: the parameter line must start with 1 (a rectangular matrix): "
                                "1 <specimens> <landmarks x 3> 0 DIM=3.")
    words = [t for t, _ in tokens]
    dimension = next((w.upper().split("=", 1)[1] for w in words[:7] if w.upper().startswith("DIM=")), "3")
    if dimension != "3":
        raise LandmarkFileError(f"{path}: DIM={dimension}; the filter needs 3D landmarks (DIM=3).")
    try:
        count, values = int(words[1].rstrip("Ll")), int(words[2].rstrip("Ll"))
        has_missing = words[3] == "1"
    except ValueError:
        raise LandmarkFileError(f"{path}, line {tokens[0][1]}: the parameter line {' '.join(words[:5])!r} is not "
                                "1 <specimens> <landmarks x 3> 0|1 ... DIM=3.") from None
    missing_code = words[4] if has_missing else None
    position = 4 + has_missing + any(w.upper().startswith("DIM=") for w in words[4:6])
    labels = []
    if words[1][-1:] in "Ll":
        labels, position = words[position:position + count], position + count
    if words[2][-1:] in "Ll":
        position += values
    data = tokens[position:]
    if values % 3 or len(data) != count * values:
        raise LandmarkFileError(f"{path}: {count} specimens of {values} values (landmarks x 3) need {count * values} "
                                f"numbers after the labels, and {len(data)} follow.")
    specimens = []
    for index in range(count):
        row = [t for t, _ in data[index * values:(index + 1) * values]]
        row = ["NA" if missing_code is not None and v == missing_code else v for v in row]
        specimens.append(_Specimen([row[i:i + 3] for i in range(0, values, 3)], data[index * values][1],
                                   labels[index] if labels else None))
    return specimens


def read_nts(text: str, path: str, specimen: str | int | None = None) -> LandmarkSet:
    """One specimen of an NTS file (see :func:`_nts_specimens`): landmarks named 1..k."""
    chosen = _chosen_specimen(_nts_specimens(text, path), path, specimen)
    return _specimen_landmarks(chosen, lambda index: f"{path}, line {chosen.line}, landmark {index}")


def write_nts(landmarks: LandmarkSet) -> str:
    values = " ".join(" ".join(repr(float(v)) for v in lm.position) if lm.placed else "-999 -999 -999"
                      for lm in landmarks.landmarks)
    return f'" written by filter_symblend\n1 1L {3 * len(landmarks.landmarks)} 1 -999 DIM=3\nspecimen\n{values}\n'
