"""The ``symblend`` command: symmetrize a mesh from a landmark file, check and convert landmarks.

    symblend symmetrize INPUT -l LANDMARKS -o OUTPUT [--pairs PAIRS.csv] [--report REPORT.json] [filter options]
    symblend landmarks check INPUT -l LANDMARKS [--pairs PAIRS.csv]
    symblend landmarks convert IN OUT

The filter options are generated from the filter's parameter declaration.
Errors are one line on stderr, exit status 1; no output file is written then.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys
import warnings

from .errors import SymblendError
from .parameters import PARAMETERS

FRAMES = ("LPS", "RAS")


def _add_filter_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("filter options (MeshSet.generate_symmetrized_mesh)")
    for p in PARAMETERS:
        unit = f" Unit: {p.unit}." if p.unit else ""
        options = {"dest": p.name, "default": p.default, "metavar": p.name.upper(),
                   "help": f"{p.label}. {p.doc}{unit} Valid: {p.range_text()}. Default: %(default)s."}
        if p.kind == "enum":
            options["choices"] = p.choices
        elif p.kind == "float":
            options["type"] = float
        group.add_argument("--" + p.name.replace("_", "-"), **options)


def _add_landmark_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("-l", "--landmarks", required=True, type=pathlib.Path,
                        help="landmark file: .pp, .fcsv, .mrk.json, .pts or .csv")
    parser.add_argument("--pairs", type=pathlib.Path,
                        help="pair table: two-column CSV of landmark names or 1-based numbers (left, right); "
                             "default: pair by name (L_/R_ prefixes, _left/_right suffixes, any case)")
    parser.add_argument("--side-words", default="l,left,lt/r,right,rt", metavar="LEFT,.../RIGHT,...",
                        help="words that mark the left and the right side in landmark names, as a prefix "
                             "or a suffix (any case, separated by _ - . or a space); default: %(default)s")
    parser.add_argument("--midline", action="store_true",
                        help="treat landmarks without a partner as midline landmarks (held on the "
                             "symmetry plane); without it they are an error")
    parser.add_argument("--mesh-frame", choices=FRAMES, default="LPS",
                        help="coordinate system of the mesh, used only when the landmark file states one "
                             "(Slicer files); default: %(default)s, as Slicer saves models")


def _one_line(error: Exception) -> str:
    return " ".join(str(error).split())


def _load_mesh(path: pathlib.Path):
    import pymeshlab

    if not path.is_file():
        raise SymblendError(f"{path}: no such mesh file.")
    from .ply_attributes import load_mesh_with_attributes

    ms = pymeshlab.MeshSet()
    try:
        load_mesh_with_attributes(ms, path)
    except pymeshlab.PyMeshLabException as error:
        raise SymblendError(f"{path}: pymeshlab cannot read it ({_one_line(error)}).") from None
    return ms


def _snapped_pairs(ms, args):
    from .landmark_files import read_landmarks
    from .pairing import pair_by_name, read_pair_table, snap_pairs

    landmarks, frame_note = read_landmarks(args.landmarks).in_frame(args.mesh_frame)
    names = landmarks.names()
    if args.pairs:
        index_pairs = read_pair_table(args.pairs, names)
        paired = {i for pair in index_pairs for i in pair}
        unpaired = [i for i in range(len(names)) if i not in paired]
    else:
        left_words, _, right_words = args.side_words.lower().partition("/")
        if not left_words or not right_words:
            raise SymblendError(f"--side-words {args.side_words!r}: give LEFT,.../RIGHT,..., e.g. l,left/r,right.")
        index_pairs, unpaired = pair_by_name(names, tuple(left_words.split(",")), tuple(right_words.split(",")))
    snapped = snap_pairs(ms.current_mesh().vertex_matrix(), landmarks, index_pairs, unpaired,
                         midline=args.midline, source=str(args.landmarks))
    return snapped, frame_note


def _save_atomically(ms, output: pathlib.Path, attributes: list[str]) -> None:
    """Save the current mesh to a temporary name beside ``output``, then rename it."""
    import pymeshlab

    temporary = output.with_name(f".{output.stem}.symblend-partial{output.suffix}")
    options = {}
    if output.suffix.lower() == ".ply":
        options = {"save_vertex_quality": True, **{f"__ca_vs__{name.lower()}": True for name in attributes}}
    try:
        ms.save_current_mesh(str(temporary), **options)
        os.replace(temporary, output)
    except pymeshlab.PyMeshLabException as error:
        raise SymblendError(f"{output}: pymeshlab cannot write it ({_one_line(error)}).") from None
    finally:
        temporary.unlink(missing_ok=True)


def _terminal_progress(percent: float, message: str) -> None:
    """A one-line progress display on a terminal, rewritten in place."""
    bar = "#" * int(percent / 5)
    print(f"\r[{bar:<20}] {percent:3.0f}% {message:<40}", end="\n" if percent >= 100 else "",
          file=sys.stderr, flush=True)


def _symmetrize(args) -> int:
    from .attributes import optional_attribute, write_landmark_attributes
    from .hausdorff import two_way_hausdorff
    from .meshset_filter import ASYMMETRY_ATTRIBUTE, generate_symmetrized_mesh

    params = {p.name: getattr(args, p.name) for p in PARAMETERS}
    if not args.output.parent.is_dir():
        raise SymblendError(f"{args.output}: the folder {args.output.parent} does not exist; create it first.")
    ms = _load_mesh(args.input)
    snapped, frame_note = _snapped_pairs(ms, args)
    missing = [name.strip() for name in args.missing.split(",") if name.strip()]
    left_weights, right_weights = snapped.weights(missing) if missing else (None, None)
    write_landmark_attributes(ms.current_mesh(), snapped.pairs, left_weights, right_weights,
                              params["pair_attribute"], params["midline_attribute"], params["weight_attribute"])
    report = generate_symmetrized_mesh(ms, _terminal_progress if sys.stderr.isatty() else None, **params)
    report["hausdorff_input_output"] = two_way_hausdorff(ms, report["input_mesh_id"], report["output_mesh_id"])
    report["landmarks"] = {"file": str(args.landmarks), "frame": frame_note,
                           "pairs": [list(p) for p in snapped.pair_names],
                           "midline": snapped.midline_names, "missing": missing,
                           "snap_distance_max": float(snapped.snap_distances.max()),
                           "left_out_unplaced": snapped.unplaced}
    _save_atomically(ms, args.output, [ASYMMETRY_ATTRIBUTE] + [
        params[name] for name in ("pair_attribute", "midline_attribute", "weight_attribute")
        if optional_attribute(ms.current_mesh(), params[name]) is not None])
    if args.report:
        args.report.write_text(json.dumps(report, indent=2) + "\n")
    before, after = report["landmark_asymmetry_before"], report["landmark_asymmetry_after"]
    print(f"{args.output}: {report['pair_count']} pairs, mode {report['mode']}; landmark asymmetry RMS "
          f"{before['rms_relative']:.2%} -> {after['rms_relative']:.1e} of the diagonal; two-way Hausdorff "
          f"input<->output {report['hausdorff_input_output']['max']:.4g}")
    return 0


def _check(args) -> int:
    from .landmarks import check_pairs

    ms = _load_mesh(args.input)
    snapped, frame_note = _snapped_pairs(ms, args)
    print(f"{args.landmarks}: {frame_note}; {len(snapped.pair_names)} pairs, "
          f"{len(snapped.midline_names)} midline")
    for k, ((left, right), distance) in enumerate(zip(snapped.pair_names, snapped.snap_distances), start=1):
        print(f"  {k:3d}  {left} -> vertex {snapped.pairs.left[k - 1]} (snap {distance[0]:.3g})   "
              f"{right} -> vertex {snapped.pairs.right[k - 1]} (snap {distance[1]:.3g})")
    if snapped.midline_names:
        print(f"midline: {', '.join(snapped.midline_names)}")
    if snapped.unplaced:
        print(f"left out (not placed): {', '.join(snapped.unplaced)}")
    check_pairs(ms.current_mesh().vertex_matrix(), snapped.pairs)
    print("ok: the pairs can be symmetrized")
    return 0


def _convert(args) -> int:
    from .landmark_files import read_landmarks, write_landmarks

    write_landmarks(args.output, read_landmarks(args.input))
    print(f"{args.input} -> {args.output}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="symblend", description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("symmetrize", help="symmetrize a mesh from landmark pairs")
    run.add_argument("input", type=pathlib.Path, help="mesh file (any format pymeshlab reads)")
    _add_landmark_options(run)
    run.add_argument("-o", "--output", required=True, type=pathlib.Path,
                     help="output mesh; .ply keeps quality (local asymmetry) and the attributes")
    run.add_argument("--report", type=pathlib.Path, help="write the filter's report, plus Hausdorff, as JSON")
    run.add_argument("--missing", default="", metavar="NAME,NAME",
                     help="landmarks on missing or broken parts (weight 0): that side takes the "
                          "mirror shape of the other (the paper's Figure 9)")
    _add_filter_options(run)
    run.set_defaults(handler=_symmetrize)

    landmarks = commands.add_parser("landmarks", help="check or convert landmark files")
    sub = landmarks.add_subparsers(dest="landmarks_command", required=True)
    check = sub.add_parser("check", help="list pairs and snap distances; report problems")
    check.add_argument("input", type=pathlib.Path, help="mesh file")
    _add_landmark_options(check)
    check.set_defaults(handler=_check)
    convert = sub.add_parser("convert", help="convert between .pp, .fcsv, .mrk.json, .pts, .csv")
    convert.add_argument("input", type=pathlib.Path)
    convert.add_argument("output", type=pathlib.Path)
    convert.set_defaults(handler=_convert)
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always")
            warnings.showwarning = lambda message, *rest: print(f"symblend: warning: {message}", file=sys.stderr)
            return args.handler(args)
    except SymblendError as error:
        print(f"symblend: error: {_one_line(error)}", file=sys.stderr)
        return 1
    except OSError as error:
        print(f"symblend: error: {error.filename}: {error.strerror}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("symblend: interrupted; no output written", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
