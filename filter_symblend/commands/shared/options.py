"""The ``symblend`` options shared by its commands: the filter's options, generated from the parameter
declaration, and the landmark options; and ``symblend symmetrize``'s arguments, which a batch row reuses."""

from __future__ import annotations

import argparse
import pathlib

from ...parameters import PARAMETERS
from .console import RaisingParser

FRAMES = ("LPS", "RAS")


def add_filter_options(parser: argparse.ArgumentParser) -> None:
    """One option per filter parameter, from the declaration (``--mode``, ``--pairs``, ...)."""
    group = parser.add_argument_group("filter options (MeshSet.generate_symmetrized_mesh; docs: README, parameter table)")
    for p in PARAMETERS:
        unit = f", {p.unit}" if p.unit else ""
        options = {"dest": p.name, "default": p.default,
                   "help": f"{p.label}{unit}; valid {p.range_text()}".replace("%", "%%") + "; default %(default)s"}
        if p.kind == "enum":
            options["choices"] = p.choices
        else:
            options["metavar"] = {"int": "N", "float": "X", "string": "NAME"}[p.kind]
            if p.kind in ("int", "float"):
                options["type"] = int if p.kind == "int" else float
        group.add_argument("--" + p.name.replace("_", "-"), **options)


def add_landmark_options(parser: argparse.ArgumentParser, required: bool = True, note: str = "",
                          save_pair_table: bool = True) -> None:
    """The landmark file and how to pair it (``note``: added to the help of ``-l``)."""
    parser.add_argument("-l", "--landmarks", required=required, type=pathlib.Path,
                        help="landmark file: .pp, .fcsv, .mrk.json (or any markups JSON), .pts, .csv, .tps or .nts"
                             + note)
    add_specimen_option(parser)
    parser.add_argument("--pair-table", type=pathlib.Path,
                        help="pair table: two-column CSV of landmark names or 1-based numbers (left, right); "
                             "default: pair by name (L_/R_ prefixes, _left/_right suffixes, any case), or by "
                             "geometry when no name carries a side (numbered landmarks)")
    if save_pair_table:
        parser.add_argument("--save-pair-table", type=pathlib.Path, metavar="PAIRS.csv",
                            help="where pairing by geometry writes the pairs it found, as a pair table to check, "
                                 "edit and give to --pair-table; default: LANDMARKS.pairs.csv beside the output "
                                 "(beside the landmark file for landmarks check), never over an existing file")
    parser.add_argument("--side-words", default="l,left,lt/r,right,rt", metavar="LEFT,.../RIGHT,...",
                        help="words that mark the left and the right side in landmark names, as a prefix "
                             "or a suffix (any case, separated by _ - . or a space); default: %(default)s")
    parser.add_argument("--midline", action="store_true",
                        help="treat landmarks without a partner as midline landmarks (held on the "
                             "symmetry plane); without it they are an error")
    parser.add_argument("--curves", action="store_true",
                        help="numbered landmarks (NAME_1, NAME_2, ..., any separator) are curves: each is "
                             "traced along the surface and resampled into equally spaced semilandmarks; "
                             "a left curve pairs with the right curve of the same name, a curve without a "
                             "side word lies on the midline (needs --midline)")
    parser.add_argument("--curve-spacing", type=positive_length, metavar="LENGTH",
                        help="distance between semilandmarks along a curve, in mesh units; "
                             "default: 1%% of the bounding-box diagonal")
    parser.add_argument("--mesh-frame", choices=FRAMES, default="LPS",
                        help="coordinate system of the mesh, used only when the landmark file states one "
                             "(Slicer files); default: %(default)s, as Slicer saves models")
    parser.add_argument("--allow-far-landmarks", action="store_true",
                        help="snap landmarks that lie farther than 2%% of the diagonal from the surface "
                             "(without it they are an error: a wrong coordinate system or unit is likelier)")


def add_specimen_option(parser: argparse.ArgumentParser) -> None:
    """``--specimen``: which specimen of a file that holds several."""
    parser.add_argument("--specimen", metavar="ID|INDEX",
                        help="the specimen of a .tps or .nts file with several, or the markup of a Slicer markups "
                             "JSON with several (its ID, label or name, or a 1-based index); default the first, "
                             "with a warning")


def positive_length(text: str) -> float:
    """argparse type: a positive, finite length in mesh units."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive length in mesh units")
    return value


def add_missing_option(parser: argparse.ArgumentParser) -> None:
    """``--missing``: landmarks on missing or broken parts."""
    parser.add_argument("--missing", default="", metavar="NAME,NAME",
                        help="landmarks on missing or broken parts (weight 0): that side takes the "
                             "mirror shape of the other (the paper's Figure 9)")


def symmetrize_arguments(argv: list[str]) -> argparse.Namespace:
    """``argv`` (the words after ``symblend symmetrize``) parsed as that command does; bad options raise
    SymblendError."""
    parser = RaisingParser(prog="symblend symmetrize")
    add_symmetrize_arguments(parser)
    return parser.parse_args(argv)


def add_symmetrize_arguments(run: argparse.ArgumentParser) -> None:
    """Every argument of ``symblend symmetrize`` (a batch row takes the same)."""
    run.add_argument("input", type=pathlib.Path, help="mesh file (any format pymeshlab reads)")
    add_landmark_options(run, required=False, note=" (not with --pairs auto)")
    run.add_argument("-o", "--output", required=True, type=pathlib.Path,
                     help="output mesh; .ply keeps quality (local asymmetry) and the attributes")
    run.add_argument("--report", type=pathlib.Path, help="write the filter's report as JSON")
    run.add_argument("--overwrite", action="store_true", help="allow -o to name the input mesh (replaced at the end)")
    add_missing_option(run)
    add_filter_options(run)
