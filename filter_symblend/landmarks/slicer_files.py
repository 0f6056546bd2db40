"""3D Slicer's landmark files: fiducial CSV (.fcsv) of every version, and markups JSON (.mrk.json, Slicer 4.11
on), with their coordinate systems (LPS or RAS)."""

from __future__ import annotations

import csv
import io
import json

from .landmark_set import Landmark, LandmarkFileError, LandmarkSet, chosen_index, parse_number, position_of
from .text_files import csv_records

OLD_FCSV_SYSTEMS = {"0": "RAS", "1": "LPS"}
SLICER4_COLUMNS = ["id", "x", "y", "z", "ow", "ox", "oy", "oz", "vis", "sel", "lock", "label", "desc",
                   "associatednodeid"]  # an .fcsv without a columns header (Slicer 4.0-4.10)


def read_fcsv(text: str, path: str) -> LandmarkSet:
    """Slicer's fiducial CSV of any version: Slicer 3's ``label,x,y,z,sel,vis``, Slicer 4's 14 columns
    (with or without the header), Slicer 5's rows with more fields than the header (the extra ones are
    ignored); the frame from ``# CoordinateSystem`` (0/RAS, 1/LPS; RAS when absent: only Slicer 3 and
    early Slicer 4 leave it out, and both wrote RAS). A point whose coordinates are empty is not placed."""
    system, columns, landmarks = None, None, []
    for number, row in csv_records(text):
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
                columns = [c.strip().lower() for c in value.split(",")]
                absent = [axis for axis in "xyz" if axis not in columns]
                if absent:
                    raise LandmarkFileError(f"{path}, line {number}: the columns header has no "
                                            f"{', '.join(absent)} column; export the markups again from Slicer "
                                            "(3D points need x, y and z).")
            continue
        names = columns or SLICER4_COLUMNS
        record = dict(zip(names, (cell.strip() for cell in row)))
        where = f"{path}, line {number}"
        if any(axis not in record for axis in "xyz"):
            raise LandmarkFileError(f"{where}: the row has {len(row)} fields, too few for the x, y, z columns "
                                    f"({', '.join(names[:names.index('z') + 1])}); complete or delete the row.")
        texts = [record[axis] for axis in "xyz"]
        position, placed = ((0.0, 0.0, 0.0), False) if "" in texts else position_of(texts, where)
        status = next((v for k, v in record.items() if "status" in k), "defined")
        landmarks.append(Landmark(record.get("label") or f"F-{len(landmarks) + 1}", position,
                                  placed and status.lower() in ("", "defined")))
    return LandmarkSet(landmarks, system or "RAS")


def write_fcsv(landmarks: LandmarkSet) -> str:
    out = io.StringIO()
    out.write("# Markups fiducial file version = 4.11\n")
    out.write(f"# CoordinateSystem = {landmarks.coordinate_system or 'LPS'}\n")
    out.write("# columns = id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID,positionStatus\n")
    writer = csv.writer(out, lineterminator="\n")
    for index, lm in enumerate(landmarks.landmarks, start=1):
        writer.writerow([index, *(repr(float(v)) for v in lm.position), 0, 0, 0, 1, 1, 1, 0, lm.name, "", "",
                         "defined" if lm.placed else "undefined"])
    return out.getvalue()


CURVE_TYPES = ("Curve", "ClosedCurve", "OpenCurve")


def _markups(text: str, path: str) -> list[dict]:
    """The markups of a Slicer markups JSON document; LandmarkFileError if it is not one."""
    try:
        document = json.loads(text)
    except ValueError as error:
        raise LandmarkFileError(f"{path}: not valid JSON ({error}).") from None
    markups = document.get("markups") if isinstance(document, dict) else None
    if not isinstance(markups, list) or not markups or not all(isinstance(m, dict) for m in markups):
        raise LandmarkFileError(f"{path}: not a Slicer markups file (no \"markups\" list of point lists); save "
                                "the points from Slicer's Markups module (.mrk.json).")
    return markups


def read_mrk_json(text: str, path: str, specimen: str | int | None = None) -> LandmarkSet:
    """One markup of a Slicer markups JSON (Slicer 4.11 on; any suffix): chosen by ``specimen`` (its
    name, or a 1-based index) when the file holds several. The points of a curve without labels are
    named ``<curve>-1``, ``<curve>-2``, ... so that they trace a curve (``--curves``)."""
    markups = _markups(text, path)
    shown = [m.get("name") or f"{m.get('type', 'markup')} {i}" for i, m in enumerate(markups, start=1)]
    index = chosen_index([m.get("name") for m in markups], shown, path, specimen, "markups")
    markup = markups[index]
    points = markup.get("controlPoints", [])
    if not isinstance(points, list):
        raise LandmarkFileError(f"{path}: controlPoints of markup {shown[index]!r} is not a list.")
    curve = markup.get("type") in CURVE_TYPES
    landmarks = []
    for index, point in enumerate(points, start=1):
        status = point.get("positionStatus", "defined")
        where = f"{path}, control point {index} ({point.get('label', '?')})"
        position = point.get("position") or [0.0, 0.0, 0.0]
        if status == "defined" and len(position) != 3:
            raise LandmarkFileError(f"{where}: position must have 3 coordinates.")
        default = f"{markup.get('name') or 'curve'}-{index}" if curve else f"F-{index}"
        landmarks.append(Landmark(point.get("label") or default,
                                  tuple(parse_number(v, where) for v in position[:3]), status == "defined"))
    return LandmarkSet(landmarks, markup.get("coordinateSystem", "LPS"))


def write_mrk_json(landmarks: LandmarkSet) -> str:
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
