"""A study's manifest: a CSV with a header, ``mesh`` (required), ``landmarks`` (optional) and any option of
``symblend symmetrize`` as a column, which overrides the study's defaults for that row; paths relative to
the manifest's folder. Each row becomes the ``symblend symmetrize`` words that run it."""

from __future__ import annotations

import argparse
import dataclasses
import os
import pathlib

from ...errors import SymblendError
from ...landmarks.text_files import csv_records, read_text
from .options import add_symmetrize_arguments

PATH_COLUMNS = ("mesh", "landmarks", "pair_table")
OUTPUT_OPTIONS = ("output", "report", "overwrite", "help", "save_pair_table")  # set by the batch, not by a row
TRUE_WORDS = {"1", "true", "yes", "y", "x"}
FALSE_WORDS = {"", "0", "false", "no", "n"}


@dataclasses.dataclass(frozen=True)
class Row:
    """One specimen: its mesh, the ``symblend symmetrize`` words that run it, and what it writes."""

    mesh: pathlib.Path
    arguments: tuple[str, ...]
    output: pathlib.Path
    report: pathlib.Path
    inputs: tuple[pathlib.Path, ...]  # files whose change makes the row out of date

    def done(self) -> bool:
        """Whether its output and report exist and are newer than every input."""
        if not (self.output.exists() and self.report.exists()):
            return False
        written = min(self.output.stat().st_mtime, self.report.stat().st_mtime)
        return all(not path.exists() or path.stat().st_mtime <= written for path in self.inputs)


def _option_table() -> dict[str, argparse.Action]:
    """``symblend symmetrize``'s options by destination name (``pair_table``, ``mode``, ...)."""
    parser = argparse.ArgumentParser(add_help=False)
    add_symmetrize_arguments(parser)
    return {action.dest: action for action in parser._actions if action.option_strings}


def _words(action: argparse.Action, value: str, where: str) -> list[str]:
    """The command-line words of one option given as a manifest cell (flags: true/false words)."""
    if action.nargs == 0:
        text = value.strip().lower()
        if text not in TRUE_WORDS | FALSE_WORDS:
            raise SymblendError(f"{where}: {value!r} for the flag `{action.dest}`; write true or false.")
        return [action.option_strings[-1]] if text in TRUE_WORDS else []
    return [] if not value.strip() else [action.option_strings[-1], value.strip()]


def read_manifest(manifest: str | os.PathLike, outdir: str | os.PathLike, defaults: list[str] = ()) -> list[Row]:
    """The rows of ``manifest`` (see the module docstring), writing to ``outdir``; ``defaults``: words of
    ``symblend symmetrize`` options for every row, which a row's own columns override."""
    manifest, outdir = pathlib.Path(manifest), pathlib.Path(outdir)
    table = csv_records(read_text(manifest, "a manifest is a CSV table with a header row"))
    columns = [c.strip() for c in table[0][1]] if table else []
    if "mesh" not in columns:
        raise SymblendError(f"{manifest}: needs a header row with a `mesh` column (and optionally landmarks and "
                            f"any option of symblend symmetrize); got {', '.join(columns) or 'no rows'}.")
    options = {dest: action for dest, action in _option_table().items() if dest not in OUTPUT_OPTIONS}
    bad = [c for c in columns if c and c != "mesh" and c.replace("-", "_") not in options]
    if bad:
        raise SymblendError(f"{manifest}: column {bad[0]!r} is not an option of symblend symmetrize (the outputs go "
                            f"to OUTDIR); valid columns: mesh, {', '.join(sorted(options))}.")
    rows, stems = [], {}
    for number, record in table[1:]:
        where = f"{manifest}, line {number}"
        cells = {column.replace("-", "_"): value for column, value in zip(columns, record) if column}
        cells.setdefault("mesh", "")
        if not cells["mesh"].strip():
            raise SymblendError(f"{where}: the mesh cell is empty.")
        for column in PATH_COLUMNS:
            if cells.get(column, "").strip():
                cells[column] = str(manifest.parent / cells[column].strip())
        mesh = pathlib.Path(cells.pop("mesh"))
        if mesh.stem in stems:
            raise SymblendError(f"{where}: {mesh.name} has the same name as the mesh of line {stems[mesh.stem]}; "
                                "both would write OUTDIR/" + mesh.stem + ".ply. Rename one.")
        stems[mesh.stem] = number
        words = list(defaults)
        for column, value in cells.items():
            words += _words(options[column], value, where)
        output, report = outdir / f"{mesh.stem}.ply", outdir / f"{mesh.stem}.json"
        inputs = tuple(pathlib.Path(cells[c]) for c in ("landmarks", "pair_table") if cells.get(c, "").strip())
        rows.append(Row(mesh, (str(mesh), *words, "-o", str(output), "--report", str(report)), output, report,
                        (mesh, *inputs)))
    return rows
