"""Plain tables of named points: the IDAV Landmark Editor's .pts (a coordinate of 9999: not placed) and a
spreadsheet's .csv with a name, x, y, z header (an empty coordinate: not placed)."""

from __future__ import annotations

import csv
import io

from .landmark_set import Landmark, LandmarkFileError, LandmarkSet, parse_number, position_of
from .text_files import csv_records, lines as text_lines

MISSING_PTS_VALUE = 9999.0


def read_pts(text: str, path: str) -> LandmarkSet:
    lines = [line.split() for line in text_lines(text) if line.strip()]
    if lines and lines[0][0].lower() == "version":
        lines = lines[1:]
    if lines and len(lines[0]) == 1:
        declared = int(parse_number(lines[0][0], f"{path}, count line"))
        lines = lines[1:]
        if declared != len(lines):
            raise LandmarkFileError(f"{path}: the count line says {declared} points but {len(lines)} follow.")
    landmarks = []
    for number, fields in enumerate(lines, start=1):
        if len(fields) < 4:
            raise LandmarkFileError(f"{path}, point {number}: expected 'name x y z', got {' '.join(fields)!r}.")
        position, placed = position_of(fields[-3:], f"{path}, point {number} ({fields[0]})")
        name = " ".join(fields[:-3])
        landmarks.append(Landmark(name, position, placed))
    return LandmarkSet(landmarks)


def write_pts(landmarks: LandmarkSet) -> str:
    rows = [f"{lm.name.replace(' ', '_')} " + " ".join(
        repr(float(v)) if lm.placed else repr(MISSING_PTS_VALUE) for v in lm.position)
        for lm in landmarks.landmarks]
    return "Version 1.0\n" + f"{len(rows)}\n" + "\n".join(rows) + "\n"


def read_csv(text: str, path: str) -> LandmarkSet:
    rows = csv_records(text)
    if not rows:
        return LandmarkSet([])
    header = [cell.strip().lower() for cell in rows[0][1]]
    name_column = next((header.index(h) for h in ("name", "label", "landmark") if h in header), None)
    if name_column is None or not {"x", "y", "z"} <= set(header):
        raise LandmarkFileError(f"{path}: the first row must name the columns name (or label), x, y, z; "
                                f"got {', '.join(rows[0][1])}.")
    landmarks = []
    for number, row in rows[1:]:
        cells = dict(zip(header, row))
        placed = all(cells.get(axis, "").strip() for axis in "xyz")
        where = f"{path}, line {number}"
        position, placed = position_of([cells[axis] for axis in "xyz"], where) if placed else ((0.0, 0.0, 0.0), False)
        landmarks.append(Landmark(row[name_column].strip(), position, placed))
    return LandmarkSet(landmarks)


def write_csv(landmarks: LandmarkSet) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["name", "x", "y", "z"])
    for lm in landmarks.landmarks:
        writer.writerow([lm.name, *((repr(float(v)) for v in lm.position) if lm.placed else ("", "", ""))])
    return out.getvalue()
