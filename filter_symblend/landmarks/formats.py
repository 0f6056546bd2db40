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

Every file is read from its bytes by one rule (``text_files``): a byte-order mark, UTF-8 or
Windows-1252; lines end at LF or CRLF, or at CR in a file without LF; the CSV formats follow the csv
module's quoting rules.

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

import pathlib

from ..atomic import write_text
from .landmark_set import Landmark, LandmarkFileError, LandmarkSet
from .morphometrics_files import read_nts, read_tps, write_nts, write_tps, write_tps_study
from .pickpoints_file import read_pp, write_pp
from .point_tables import read_csv, read_pts, write_csv, write_pts
from .slicer_files import read_fcsv, read_mrk_json, write_fcsv, write_mrk_json
from .text_files import read_text

__all__ = ["FORMATS", "Landmark", "LandmarkFileError", "LandmarkSet", "read_landmarks", "write_landmarks",
           "write_tps_study"]


FORMATS = {
    ".pp": (read_pp, write_pp),
    ".fcsv": (read_fcsv, write_fcsv),
    ".mrk.json": (read_mrk_json, write_mrk_json),
    ".json": (read_mrk_json, write_mrk_json),
    ".pts": (read_pts, write_pts),
    ".csv": (read_csv, write_csv),
    ".tps": (read_tps, write_tps),
    ".nts": (read_nts, write_nts),
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
    text = read_text(path, f"landmark files are text ({', '.join(sorted(FORMATS))})")
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
