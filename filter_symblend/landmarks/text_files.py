"""Text as the programs write it: one decoding path from bytes, one rule for line ends, CSV records.

Decoding: a byte-order mark decides (UTF-8, UTF-16 LE/BE, as Notepad and PowerShell write); without one,
UTF-8, else Windows-1252 (what Excel and older Windows programs save). Bytes with a NUL, or UTF-16 that is
mostly not ASCII (every landmark format is mostly digits and separators), are not text.

Line ends: a record ends at a line feed, a carriage return before it dropped (Unix and Windows files);
a file without any line feed ends records at carriage returns (classic Mac OS). A carriage return inside a
line is part of it, as 3D Slicer reads its .fcsv files: its rows may carry one inside a description.

CSV: the csv module's rules within a record (quotes, doubled quotes, commas inside quotes), a quoted field
may span lines; the separator is a comma, or a semicolon or tab when the header row has no comma (the
European spreadsheet export, where a decimal comma is then read as a point).
"""

from __future__ import annotations

import codecs
import csv
import pathlib

from .landmark_set import LandmarkFileError

BOMS = ((codecs.BOM_UTF8, "utf-8-sig"), (codecs.BOM_UTF16_LE, "utf-16"), (codecs.BOM_UTF16_BE, "utf-16"))
_CR = "\ue000"  # stands in for a carriage return inside a record while the csv module reads it


def read_text(path: pathlib.Path, what: str) -> str:
    """The decoded text of the file ``path`` (see the module docstring); ``what`` names the kind of
    file in the refusal of one that is not text. LandmarkFileError if it cannot be read."""
    try:
        data = path.read_bytes()
    except OSError as error:
        raise LandmarkFileError(f"{path}: cannot be read ({error.strerror}).") from None
    text = decoded(data)
    if text is None:
        raise LandmarkFileError(f"{path}: not a text file; {what}.")
    return text


def decoded(data: bytes) -> str | None:
    """``data`` as text by the module's decoding rule, or None when it is not text."""
    encoding = next((name for bom, name in BOMS if data.startswith(bom)), None)
    if encoding == "utf-16":
        try:
            text = data.decode("utf-16")
        except UnicodeDecodeError:
            return None
        return text if "\0" not in text and sum(c < "\x80" for c in text) * 2 >= len(text) else None
    if b"\0" in data:
        return None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("cp1252", errors="replace")


def lines(text: str) -> list[str]:
    """The lines of ``text`` by the module's rule for line ends (no line end kept)."""
    if "\n" not in text:
        return text.split("\r")
    return [line[:-1] if line.endswith("\r") else line for line in text.split("\n")]


def csv_records(text: str) -> list[tuple[int, list[str]]]:
    """(line number, fields) of every non-blank record of ``text``, by the module's CSV rules; the
    separator is found on the first record that is not a ``#`` comment."""
    records, pending, start = [], "", 0
    for number, line in enumerate(lines(text), start=1):
        if not pending and line.startswith("#"):  # a comment line is one record, whatever quotes it holds
            records.append((number, line))
            continue
        pending, start = (pending + "\n" + line, start) if pending else (line, number)
        if pending.count('"') % 2 == 0:
            records.append((start, pending))
            pending = ""
    if pending:
        records.append((start, pending))
    header = next((record for _, record in records if record.strip() and not record.startswith("#")), "")
    separator = "," if "," in header else next((s for s in ";\t" if s in header), ",")
    rows = []
    for number, record in records:
        fields = next(csv.reader([record.replace("\r", _CR)], delimiter=separator), [])
        fields = [field.replace(_CR, "\r") for field in fields]
        if separator == ";":
            fields = [_decimal_point(field) for field in fields]
        if any(field.strip() for field in fields):
            rows.append((number, fields))
    return rows


def _decimal_point(field: str) -> str:
    """A number written with a decimal comma ("1,5") with a point; any other field as it is."""
    candidate = field.strip().replace(",", ".", 1)
    try:
        float(candidate)
    except ValueError:
        return field
    return candidate
