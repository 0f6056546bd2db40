"""Landmark files as users have them: read and write named 3D points.

| suffix      | program                      | "not placed" marker              | frame      |
|-------------|------------------------------|----------------------------------|------------|
| .pp         | MeshLab PickPoints (XML)     | active="0"                       | mesh       |
| .fcsv       | 3D Slicer fiducials          | a *status column != "defined"    | LPS or RAS |
| .mrk.json   | 3D Slicer / SlicerMorph      | positionStatus != "defined"      | LPS or RAS |
| .json, any  | (a markups JSON by content)  |                                  |            |
| .pts        | IDAV Landmark Editor         | a coordinate of 9999             | mesh       |
| .csv        | spreadsheet: name, x, y, z   | an empty coordinate              | mesh       |
| .tps        | Rohlf's TPS (LM3= blocks;    | a coordinate NA, -999 or 9999    | mesh       |
|             | geomorph, Morpho, MorphoJ)   |                                  |            |
| .nts        | NTSYS matrix, one specimen   | its missing-value code, or NA    | mesh       |
|             | per row (geomorph, Morpho)   |                                  |            |

In every format a coordinate written NA, NaN, -999 or 9999 (as morphometric
software writes a missing landmark) marks the landmark as not placed. A .tps or .nts
file may hold several specimens: one is chosen by ID or 1-based index
(default the first, with a warning naming the others); its landmarks are named
by number, 1..k, so pair tables by number work; SCALE= is applied. A markups JSON
may hold several markups: one is chosen the same way (by name or index).

``coordinate_system`` is "LPS", "RAS" or None (the mesh's own frame). Slicer
writes "# CoordinateSystem = 0" (RAS) or "= 1" (LPS) in old .fcsv files, and
nothing in Slicer 3's (RAS).
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
import pathlib
import warnings
import xml.etree.ElementTree as ElementTree

from ..atomic import write_text
from ..errors import SymblendError, SymblendWarning

MISSING_PTS_VALUE = 9999.0
MISSING_WORDS = {"na", "nan", "-999", "-999.0", "9999", "9999.0"}  # a missing coordinate, as the field writes it
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


def _missing(text) -> bool:
    """Whether a coordinate's text marks a missing landmark (NA, NaN, -999, 9999)."""
    return text is not None and str(text).strip().lower() in MISSING_WORDS


def _position(texts, where: str) -> tuple[tuple[float, float, float], bool]:
    """(x, y, z) and whether the landmark is placed, from three coordinate texts (missing: zeros, False)."""
    if any(_missing(t) for t in texts):
        return (0.0, 0.0, 0.0), False
    return tuple(_number(t, where) for t in texts), True


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
        position, placed = _position([point.get(axis) for axis in "xyz"], where)
        landmarks.append(Landmark(point.get("name", f"point_{index}"), position,
                                  placed and point.get("active", "1") != "0"))
    return LandmarkSet(landmarks)


def _write_pp(landmarks: LandmarkSet) -> str:
    root = ElementTree.Element("PickedPoints")
    ElementTree.SubElement(root, "DocumentData")
    for lm in landmarks.landmarks:
        x, y, z = (repr(float(v)) for v in lm.position)
        ElementTree.SubElement(root, "point", name=lm.name, active="1" if lm.placed else "0", x=x, y=y, z=z)
    ElementTree.indent(root)
    return "<!DOCTYPE PickedPoints>\n" + ElementTree.tostring(root, encoding="unicode") + "\n"


SLICER4_COLUMNS = ["id", "x", "y", "z", "ow", "ox", "oy", "oz", "vis", "sel", "lock", "label", "desc",
                   "associatednodeid"]  # an .fcsv without a columns header (Slicer 4.0-4.10)


def _read_fcsv(text: str, path: str) -> LandmarkSet:
    """Slicer's fiducial CSV of any version: Slicer 3's ``label,x,y,z,sel,vis``, Slicer 4's 14 columns
    (with or without the header), Slicer 5's rows with more fields than the header (the extra ones are
    ignored); the frame from ``# CoordinateSystem`` (0/RAS, 1/LPS; RAS when absent: only Slicer 3 and
    early Slicer 4 leave it out, and both wrote RAS). A point whose coordinates are empty is not placed."""
    system, columns, landmarks = None, None, []
    rows = list(csv.reader(io.StringIO(text)))
    for number, row in enumerate(rows, start=1):
        if not row or not any(cell.strip() for cell in row):
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
        position, placed = ((0.0, 0.0, 0.0), False) if "" in texts else _position(texts, where)
        status = next((v for k, v in record.items() if "status" in k), "defined")
        landmarks.append(Landmark(record.get("label") or f"F-{len(landmarks) + 1}", position,
                                  placed and status.lower() in ("", "defined")))
    return LandmarkSet(landmarks, system or "RAS")


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


def _read_mrk_json(text: str, path: str, specimen: str | int | None = None) -> LandmarkSet:
    """One markup of a Slicer markups JSON (Slicer 4.11 on; any suffix): chosen by ``specimen`` (its
    name, or a 1-based index) when the file holds several. The points of a curve without labels are
    named ``<curve>-1``, ``<curve>-2``, ... so that they trace a curve (``--curves``)."""
    markups = _markups(text, path)
    shown = [m.get("name") or f"{m.get('type', 'markup')} {i}" for i, m in enumerate(markups, start=1)]
    index = _chosen([m.get("name") for m in markups], shown, path, specimen, "markups")
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
        position, placed = _position(fields[-3:], f"{path}, point {number} ({fields[0]})")
        name = " ".join(fields[:-3])
        landmarks.append(Landmark(name, position, placed))
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
        position, placed = _position([cells[axis] for axis in "xyz"], where) if placed else ((0.0, 0.0, 0.0), False)
        landmarks.append(Landmark(row[name_column].strip(), position, placed))
    return LandmarkSet(landmarks)


def _write_csv(landmarks: LandmarkSet) -> str:
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["name", "x", "y", "z"])
    for lm in landmarks.landmarks:
        writer.writerow([lm.name, *((repr(float(v)) for v in lm.position) if lm.placed else ("", "", ""))])
    return out.getvalue()


@dataclasses.dataclass
class _Specimen:
    rows: list[list[str]]  # coordinate texts per landmark
    line: int  # line of its LM3= line
    identifier: str | None = None
    scale: float = 1.0


def _tps_specimens(text: str, path: str) -> list[_Specimen]:
    """The specimens of a TPS file, in order; 2D files (LM=) are refused."""
    specimens, lines, number = [], text.splitlines(), 0
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
            scale = _number(value, f"{path}, line {number} (SCALE)")
            if scale <= 0:
                raise LandmarkFileError(f"{path}, line {number}: SCALE={value.strip()} must be positive.")
            specimens[-1].scale = scale
    return specimens


def _chosen(identifiers: list[str | None], shown: list[str], path: str, specimen: str | int | None,
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


def _chosen_specimen(specimens: list[_Specimen], path: str, specimen: str | int | None) -> _Specimen:
    if not specimens:
        raise LandmarkFileError(f"{path}: no LM3= block; a TPS file of 3D landmarks starts each specimen with "
                                "LM3=<count>.")
    identifiers = [s.identifier for s in specimens]
    shown = [s.identifier or str(i) for i, s in enumerate(specimens, start=1)]
    return specimens[_chosen(identifiers, shown, path, specimen)]


def _specimen_landmarks(chosen: _Specimen, where) -> LandmarkSet:
    """A specimen's landmarks, named 1..k, its scale applied; ``where(k)`` names landmark k's place in
    messages."""
    landmarks = []
    for index, row in enumerate(chosen.rows, start=1):
        position, placed = _position(row, where(index))
        landmarks.append(Landmark(str(index), tuple(chosen.scale * v for v in position), placed))
    return LandmarkSet(landmarks)


def read_tps(text: str, path: str, specimen: str | int | None = None) -> LandmarkSet:
    """One specimen of a TPS file (see the module docstring): landmarks named 1..k, SCALE applied."""
    chosen = _chosen_specimen(_tps_specimens(text, path), path, specimen)
    return _specimen_landmarks(chosen, lambda index: f"{path}, line {chosen.line + index}")


def _write_tps(landmarks: LandmarkSet, identifier: str = "specimen") -> str:
    rows = [" ".join(repr(float(v)) for v in lm.position) if lm.placed else "NA NA NA" for lm in landmarks.landmarks]
    return f"LM3={len(rows)}\n" + "".join(row + "\n" for row in rows) + f"ID={identifier}\n"


def write_tps_study(path, specimens: dict[str, LandmarkSet]) -> None:
    """Several specimens (ID -> landmarks) in one TPS file, as geomorph's readland.tps and Morpho's
    readallTPS read them (missing coordinates as NA)."""
    write_text(path, "".join(_write_tps(landmarks, identifier) for identifier, landmarks in specimens.items()))


def _nts_specimens(text: str, path: str) -> list[_Specimen]:
    """The specimens of an NTS file in the multiple-specimen format (Rohlf): a parameter line
    ``1 n[L] p*k[L] 0|1 [missing code] DIM=3``, then the labels (if L), then n rows of p*k values; text
    after a double quote is a comment."""
    tokens = []
    for number, line in enumerate(text.splitlines(), start=1):
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


def _write_nts(landmarks: LandmarkSet) -> str:
    values = " ".join(" ".join(repr(float(v)) for v in lm.position) if lm.placed else "-999 -999 -999"
                      for lm in landmarks.landmarks)
    return f'" written by filter_symblend\n1 1L {3 * len(landmarks.landmarks)} 1 -999 DIM=3\nspecimen\n{values}\n'


FORMATS = {
    ".pp": (_read_pp, _write_pp),
    ".fcsv": (_read_fcsv, _write_fcsv),
    ".mrk.json": (_read_mrk_json, _write_mrk_json),
    ".json": (_read_mrk_json, _write_mrk_json),
    ".pts": (_read_pts, _write_pts),
    ".csv": (_read_csv, _write_csv),
    ".tps": (read_tps, _write_tps),
    ".nts": (read_nts, _write_nts),
}


def _format_of(path: pathlib.Path) -> str:
    name = path.name.lower()
    for suffix in sorted(FORMATS, key=len, reverse=True):
        if name.endswith(suffix):
            return suffix
    raise LandmarkFileError(f"{path}: unknown landmark format; use one of {', '.join(sorted(FORMATS))}.")


SEVERAL_SETS = (".tps", ".nts", ".mrk.json", ".json")  # formats whose files may hold several sets of landmarks


def read_landmarks(path, specimen: str | int | None = None) -> LandmarkSet:
    """Read a landmark file; the format comes from the suffix (see the module table), except that a
    Slicer markups JSON is recognised by its content whatever its name. ``specimen`` (an ID or name, or
    a 1-based index) chooses one specimen of a .tps or .nts file, or one markup of a markups JSON."""
    path = pathlib.Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as error:
        raise LandmarkFileError(f"{path}: cannot be read ({error.strerror}).") from None
    except UnicodeDecodeError:
        raise LandmarkFileError(f"{path}: not a text file; landmark files are text "
                                f"({', '.join(sorted(FORMATS))}).") from None
    suffix = ".json" if text.lstrip().startswith("{") else _format_of(path)
    if specimen is not None and suffix not in SEVERAL_SETS:
        raise LandmarkFileError(f"{path}: --specimen chooses a specimen of a .tps or .nts file, or a markup of a "
                                "Slicer markups JSON; this file holds one set of landmarks. Leave it out.")
    if suffix in SEVERAL_SETS:
        return FORMATS[suffix][0](text, str(path), specimen)
    return FORMATS[suffix][0](text, str(path))


def write_landmarks(path, landmarks: LandmarkSet) -> None:
    """Write ``landmarks`` in the format of the suffix, all at once (no partial file on error)."""
    write_text(path, FORMATS[_format_of(pathlib.Path(path))][1](landmarks))
