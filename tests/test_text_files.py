"""Files as other programs write them: every landmark format, the pair table and the batch manifest read the
same whatever the line ends, byte-order mark, encoding, trailing separators, quoting and line breaks inside
fields. Each file is written here byte for byte."""

import codecs

import pytest

from filter_symblend.commands.batch import read_manifest
from filter_symblend.landmarks.formats import LandmarkFileError, read_landmarks
from filter_symblend.landmarks.pairing import read_pair_table

NAMES = ["L_orbitale", "R_orbitale", "nasion"]
POSITIONS = [(1.25, -2.5, 3.0), (-1.25, -2.5, 3.0), (0.0, 4.0, 1e-07)]

# each format's file as a list of lines (no line ends), in plain UTF-8
FILES = {
    ".fcsv": ["# Markups fiducial file version = 5.6", "# CoordinateSystem = LPS",
              "# columns = id,x,y,z,ow,ox,oy,oz,vis,sel,lock,label,desc,associatedNodeID",
              *(f"{i},{x},{y},{z},0,0,0,1,1,1,0,{n},,vtkMRMLModelNode4"
                for i, (n, (x, y, z)) in enumerate(zip(NAMES, POSITIONS), start=1))],
    ".csv": ["name,x,y,z", *(f"{n},{x},{y},{z}" for n, (x, y, z) in zip(NAMES, POSITIONS))],
    ".pts": ["Version 1.0", "3", *(f"{n} {x} {y} {z}" for n, (x, y, z) in zip(NAMES, POSITIONS))],
    ".tps": ["LM3=3", *(f"{x} {y} {z}" for x, y, z in POSITIONS), "ID=skull_1"],
    ".nts": ['" a study', "1 1L 9 0 DIM=3", "skull_1", " ".join(f"{x} {y} {z}" for x, y, z in POSITIONS)],
    ".pp": ["<!DOCTYPE PickedPoints>", "<PickedPoints>",
            *(f' <point x="{x}" y="{y}" z="{z}" active="1" name="{n}"/>' for n, (x, y, z) in zip(NAMES, POSITIONS)),
            "</PickedPoints>"],
    ".mrk.json": ['{"markups": [{"type": "Fiducial", "coordinateSystem": "LPS", "controlPoints": [',
                  ",\n".join(f'{{"label": "{n}", "position": [{x}, {y}, {z}]}}'
                             for n, (x, y, z) in zip(NAMES, POSITIONS)), "]}]}"],
}
NUMBERED = (".tps", ".nts")  # formats whose landmarks are named by number

LINE_ENDS = {"LF": "\n", "CRLF": "\r\n", "CR (classic Mac)": "\r"}
ENCODINGS = {"UTF-8": "utf-8", "UTF-8 with BOM": "utf-8-sig", "UTF-16 LE with BOM": "utf-16"}


def _read(tmp_path, suffix, data: bytes):
    path = tmp_path / f"points{suffix}"
    path.write_bytes(data)
    return read_landmarks(path)


def _assert_read_right(landmarks, names):
    assert landmarks.names() == names
    assert [lm.position for lm in landmarks.landmarks] == POSITIONS
    assert all(lm.placed for lm in landmarks.landmarks)


@pytest.mark.parametrize("encoding", ENCODINGS)
@pytest.mark.parametrize("line_end", LINE_ENDS)
@pytest.mark.parametrize("suffix", FILES)
def test_every_format_reads_the_same_whatever_the_line_ends_and_encoding(tmp_path, suffix, line_end, encoding):
    text = LINE_ENDS[line_end].join(FILES[suffix]) + LINE_ENDS[line_end]
    landmarks = _read(tmp_path, suffix, text.encode(ENCODINGS[encoding]))
    _assert_read_right(landmarks, ["1", "2", "3"] if suffix in NUMBERED else NAMES)


def test_a_slicer_fcsv_with_carriage_returns_inside_its_descriptions(tmp_path):
    """Slicer reads rows up to a line feed; a description edited on Windows keeps a bare CR inside it."""
    rows = FILES[".fcsv"][:3] + [row.replace(",,vtk", ",left orbit\rlowest point,vtk") for row in FILES[".fcsv"][3:]]
    for line_end in ("\n", "\r\n"):
        _assert_read_right(_read(tmp_path, ".fcsv", (line_end.join(rows) + line_end).encode()), NAMES)


@pytest.mark.parametrize("suffix", [".fcsv", ".csv"])
def test_csv_formats_take_quotes_trailing_separators_and_line_breaks_inside_quotes(tmp_path, suffix):
    names = ["L, orbitale", 'R "orbitale"', "nasion"]
    quoted = ['"L, orbitale"', '"R ""orbitale"""', "nasion"]
    if suffix == ".fcsv":
        rows = FILES[".fcsv"][:3] + [f'{i},{x},{y},{z},0,0,0,1,1,1,0,{q},"two\r\nlines, quoted",vtkMRMLModelNode4,'
                                     for i, (q, (x, y, z)) in enumerate(zip(quoted, POSITIONS), start=1)]
    else:
        rows = ["name,x,y,z,note,"] + [f'{q},{x},{y},{z},"Alt+Enter\nin Excel",'
                                       for q, (x, y, z) in zip(quoted, POSITIONS)]
    _assert_read_right(_read(tmp_path, suffix, ("\r\n".join(rows) + "\r\n").encode()), names)


@pytest.mark.parametrize("encoding", ["utf-8", "utf-8-sig", "cp1252", "utf-16"])
@pytest.mark.parametrize("suffix", [".csv", ".fcsv", ".pts", ".pp", ".mrk.json"])
def test_non_ascii_names_in_every_encoding_a_program_writes(tmp_path, suffix, encoding):
    names = ["L_sphénoïde", "R_sphénoïde", "Näsion"]
    text = "\n".join(FILES[suffix])
    for old, new in zip(NAMES, names):
        text = text.replace(old, new)
    _assert_read_right(_read(tmp_path, suffix, text.encode(encoding)), names)


def test_a_european_spreadsheet_with_semicolons_and_decimal_commas(tmp_path):
    rows = ["name;x;y;z"] + [f"{n};{x};{y};{z}".replace(".", ",") for n, (x, y, z) in zip(NAMES, POSITIONS)]
    _assert_read_right(_read(tmp_path, ".csv", ("\r\n".join(rows) + "\r\n").encode("cp1252")), NAMES)


def test_files_that_are_not_text_are_refused_by_name(tmp_path):
    for data in (b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n\0\0\x80?",
                 codecs.BOM_UTF16_LE + "\u4e00\u4e8c\u4e09\u56db".encode("utf-16-le")):
        with pytest.raises(LandmarkFileError, match=r"points.fcsv: not a text file; landmark files are text"):
            _read(tmp_path, ".fcsv", data)


@pytest.mark.parametrize("line_end", LINE_ENDS.values())
def test_a_pair_table_with_any_line_ends_a_bom_and_trailing_separators(tmp_path, line_end):
    names = ["L_a", "R_a", "L, b", "R, b"]
    table = tmp_path / "pairs.csv"
    table.write_bytes(codecs.BOM_UTF8 + line_end.join(["left,right,", "L_a,R_a,", '"L, b","R, b",', ""]).encode())
    assert read_pair_table(table, names) == [(0, 1), (2, 3)]
    table.write_bytes(line_end.join(["left;right", "1;2", "3;4"]).encode())
    assert read_pair_table(table, names) == [(0, 1), (2, 3)]
    table.write_bytes(b"\0\0")
    with pytest.raises(LandmarkFileError, match=r"pairs.csv: not a text file; a pair table is a CSV of two columns"):
        read_pair_table(table, names)


@pytest.mark.parametrize("line_end", LINE_ENDS.values())
def test_a_manifest_from_a_spreadsheet_reads_with_any_line_ends(tmp_path, line_end):
    rows = ["mesh,landmarks,mode,", "skull 1.ply,skull 1.pp,,", '"skull, 2.ply",,standard,', ""]
    (tmp_path / "m.csv").write_bytes(codecs.BOM_UTF8 + line_end.join(rows).encode())
    first, second = read_manifest(tmp_path / "m.csv", tmp_path / "out")
    assert first.mesh.name == "skull 1.ply" and str(tmp_path / "skull 1.pp") in first.arguments
    assert second.mesh.name == "skull, 2.ply" and second.arguments[1:3] == ("--mode", "standard")
    (tmp_path / "m.csv").write_bytes(b"PK\x03\x04\x00\x00")  # a spreadsheet saved as .xlsx, renamed
    with pytest.raises(LandmarkFileError, match=r"m.csv: not a text file; a manifest is a CSV table with a header row"):
        read_manifest(tmp_path / "m.csv", tmp_path / "out")
