"""Landmark files as users have them: read and write named 3D points.

| suffix      | program                      | "not placed" marker              | frame      |
|-------------|------------------------------|----------------------------------|------------|
| .pp         | MeshLab PickPoints (XML)     | active="0"                       | mesh       |
| .fcsv       | 3D Slicer fiducials          | a *status column != "defined"    | LPS or RAS |
| .mrk.json   | 3D Slicer / SlicerMorph      | positionStatus != "defined"      | LPS or RAS |
| .pts        | IDAV Landmark Editor         | a coordinate of 9999             | mesh       |
| .csv        | spreadsheet: name, x, y, z   | an empty coordinate              | mesh       |

``coordinate_system`` is "LPS", "RAS" or None (the mesh's own frame). Slicer
writes "# CoordinateSystem = 0" (RAS) or "= 1" (LPS) in old .fcsv files.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
import pathlib
import xml.etree.ElementTree as ElementTree

from ..errors import SymblendError

MISSING_PTS_VALUE = 9999.0
OLD_FCSV_SYSTEMS = {"0": "RAS", "1": "LPS"}


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


def _number(text: str, where: str) -> float:
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise LandmarkFileError(f"{where}: {text!r} is not a number.") from None
    if not math.isfinite(value):
        raise LandmarkFileError(f"{where}: coordinate {text!r} is not finite.")
    return value


def _read_pp(text: str, path: str) -> LandmarkSet:
    try:
        root = ElementTree.fromstring(text)
    except ElementTree.ParseError as error:
        raise LandmarkFileError(f"{path}: not a valid PickPoints XML file ({error}).") from None
    landmarks = []
    for index, point in enumerate(root.iter("point"), start=1):
        where = f"{path}, point {index} ({point.get('name', '?')})"
        position = tuple(_number(point.get(axis), where) for axis in "xyz")
        landmarks.append(Landmark(point.get("name", f"point_{index}"), position,
                                  point.get("active", "1") != "0"))
    return LandmarkSet(landmarks)


def _write_pp(landmarks: LandmarkSet) -> str:
    root = ElementTree.Element("PickedPoints")
    ElementTree.SubElement(root, "DocumentData")
    for lm in landmarks.landmarks:
        x, y, z = (repr(float(v)) for v in lm.position)
        ElementTree.SubElement(root, "point", name=lm.name, active="1" if lm.placed else "0", x=x, y=y, z=z)
    ElementTree.indent(root)
    return "<!DOCTYPE PickedPoints>\n" + ElementTree.tostring(root, encoding="unicode") + "\n"


def _read_fcsv(text: str, path: str) -> LandmarkSet:
    system, columns, landmarks = None, None, []
    rows = list(csv.reader(io.StringIO(text)))
    for number, row in enumerate(rows, start=1):
        if not row:
            continue
        if row[0].startswith("#"):
            header = ",".join(row).lstrip("#").strip()
            key, _, value = header.partition("=")
            key, value = key.strip().lower(), value.strip()
            if key == "coordinatesystem":
                system = OLD_FCSV_SYSTEMS.get(value, value.upper())
                if system not in ("LPS", "RAS"):
                    raise LandmarkFileError(f"{path}, line {number}: coordinate system {value!r} is not "
                                            "LPS or RAS; export the points in LPS or RAS from Slicer.")
            elif key == "columns":
                columns = [c.strip() for c in value.split(",")]
                absent = [axis for axis in "xyz" if axis not in columns]
                if absent:
                    raise LandmarkFileError(f"{path}, line {number}: the columns header has no "
                                            f"{', '.join(absent)} column; export the markups again from Slicer "
                                            "(3D points need x, y and z).")
            continue
        names = columns or ["id", "x", "y", "z", "ow", "ox", "oy", "oz", "vis", "sel", "lock", "label"]
        record = dict(zip(names, row))
        where = f"{path}, line {number}"
        position = tuple(_number(record.get(axis), where) for axis in "xyz")
        status = next((v for k, v in record.items() if "status" in k.lower()), "defined")
        landmarks.append(Landmark(record.get("label") or f"F-{len(landmarks) + 1}", position,
                                  status.strip().lower() in ("", "defined")))
    return LandmarkSet(landmarks, system or "LPS")


def _write_fcsv(landmarks: LandmarkSet) -> str:
    out = io.StringIO()
    out.write("# Markups fiducial file version = 4.11\n")
    out.write(f"# CoordinateSystem = {landmarks.coordinate_system or 'LPS'}\n")
    out.write("# columns = id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID,positionStatus\n")
    writer = csv.writer(out, lineterminator="\n")
    for index, lm in enumerate(landmarks.landmarks, start=1):
        writer.writerow([index, *(repr(float(v)) for v in lm.position), 0, 0, 0, 1, 1, 1, 0, lm.name, "", "",
                         "defined" if lm.placed else "undefined"])
    return out.getvalue()


def _read_mrk_json(text: str, path: str) -> LandmarkSet:
    try:
        document = json.loads(text)
        markup = document["markups"][0]
        points = markup.get("controlPoints", [])
    except (ValueError, KeyError, IndexError, TypeError):
        raise LandmarkFileError(f"{path}: not a Slicer markups file (no markups[0].controlPoints).") from None
    landmarks = []
    for index, point in enumerate(points, start=1):
        status = point.get("positionStatus", "defined")
        where = f"{path}, control point {index} ({point.get('label', '?')})"
        position = point.get("position") or [0.0, 0.0, 0.0]
        if status == "defined" and len(position) != 3:
            raise LandmarkFileError(f"{where}: position must have 3 coordinates.")
        landmarks.append(Landmark(point.get("label") or f"F-{index}",
                                  tuple(_number(v, where) for v in position[:3]), status == "defined"))
    return LandmarkSet(landmarks, markup.get("coordinateSystem", "LPS"))


def _write_mrk_json(landmarks: LandmarkSet) -> str:
    points = [{"id": str(i), "label": lm.name, "position": [float(v) for v in lm.position],
               "positionStatus": "defined" if lm.placed else "undefined"}
              for i, lm in enumerate(landmarks.landmarks, start=1)]
    document = {
        "@schema": "https://raw.githubusercontent.com/slicer/slicer/master/Modules/Loadable/Markups/"
                   "Resources/Schema/markups-schema-v1.0.3.json#",
        "markups": [{"type": "Fiducial", "coordinateSystem": landmarks.coordinate_system or "LPS",
                     "controlPoints": points}],
    }
    return json.dumps(document, indent=2) + "\n"


def _read_pts(text: str, path: str) -> LandmarkSet:
    lines = [line.split() for line in text.splitlines() if line.strip()]
    if lines and lines[0][0].lower() == "version":
        lines = lines[1:]
    if lines and len(lines[0]) == 1:
        declared = int(_number(lines[0][0], f"{path}, count line"))
        lines = lines[1:]
        if declared != len(lines):
            raise LandmarkFileError(f"{path}: the count line says {declared} points but {len(lines)} follow.")
    landmarks = []
    for number, fields in enumerate(lines, start=1):
        if len(fields) < 4:
            raise LandmarkFileError(f"{path}, point {number}: expected 'name x y z', got {' '.join(fields)!r}.")
        position = tuple(_number(v, f"{path}, point {number} ({fields[0]})") for v in fields[-3:])
        name = " ".join(fields[:-3])
        landmarks.append(Landmark(name, position, MISSING_PTS_VALUE not in position))
    return LandmarkSet(landmarks)


def _write_pts(landmarks: LandmarkSet) -> str:
    rows = [f"{lm.name.replace(' ', '_')} " + " ".join(
        repr(float(v)) if lm.placed else repr(MISSING_PTS_VALUE) for v in lm.position)
        for lm in landmarks.landmarks]
    return "Version 1.0\n" + f"{len(rows)}\n" + "\n".join(rows) + "\n"


def _read_csv(text: str, path: str) -> LandmarkSet:
    rows = [row for row in csv.reader(io.StringIO(text)) if row and any(cell.strip() for cell in row)]
    if not rows:
        return LandmarkSet([])
    header = [cell.strip().lower() for cell in rows[0]]
    name_column = next((header.index(h) for h in ("name", "label", "landmark") if h in header), None)
    if name_column is None or not {"x", "y", "z"} <= set(header):
        raise LandmarkFileError(f"{path}: the first row must name the columns name (or label), x, y, z; "
                                f"got {', '.join(rows[0])}.")
    landmarks = []
    for number, row in enumerate(rows[1:], start=2):
        cells = dict(zip(header, row))
        placed = all(cells.get(axis, "").strip() for axis in "xyz")
        where = f"{path}, line {number}"
        position = tuple(_number(cells[axis], where) if placed else 0.0 for axis in "xyz")
        landmarks.append(Landmark(row[name_column].strip(), position, placed))
    return LandmarkSet(landmarks)


def _write_csv(landmarks: LandmarkSet) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["name", "x", "y", "z"])
    for lm in landmarks.landmarks:
        writer.writerow([lm.name, *((repr(float(v)) for v in lm.position) if lm.placed else ("", "", ""))])
    return out.getvalue()


FORMATS = {
    ".pp": (_read_pp, _write_pp),
    ".fcsv": (_read_fcsv, _write_fcsv),
    ".mrk.json": (_read_mrk_json, _write_mrk_json),
    ".pts": (_read_pts, _write_pts),
    ".csv": (_read_csv, _write_csv),
}


def _format_of(path: pathlib.Path) -> str:
    name = path.name.lower()
    for suffix in sorted(FORMATS, key=len, reverse=True):
        if name.endswith(suffix):
            return suffix
    raise LandmarkFileError(f"{path}: unknown landmark format; use one of {', '.join(sorted(FORMATS))}.")


def read_landmarks(path) -> LandmarkSet:
    """Read a landmark file; the format comes from the suffix (see the module table)."""
    path = pathlib.Path(path)
    reader = FORMATS[_format_of(path)][0]
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as error:
        raise LandmarkFileError(f"{path}: cannot be read ({error.strerror}).") from None
    return reader(text, str(path))


def write_landmarks(path, landmarks: LandmarkSet) -> None:
    """Write ``landmarks`` in the format of the suffix, all at once (no partial file on error)."""
    path = pathlib.Path(path)
    text = FORMATS[_format_of(path)][1](landmarks)
    temporary = path.with_name(path.name + ".partial")
    temporary.write_text(text, encoding="utf-8")
    temporary.replace(path)
