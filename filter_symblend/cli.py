"""The symblend command: symmetrize a mesh from a landmark file or a whole study, run filter scripts,
compare before and after, check and convert landmarks.

    symblend symmetrize INPUT -l LANDMARKS -o OUTPUT [--pair-table PAIRS.csv] [--curves] [--report REPORT.json] [filter options]
    symblend symmetrize INPUT --pairs auto -o OUTPUT [--report REPORT.json] [filter options]
    symblend batch MANIFEST.csv -o OUTDIR [--workers N] [--scheduler ADDRESS] [--force] [symmetrize options]
    symblend mlx SCRIPT.mlx INPUT [-l LANDMARKS] -o OUTPUT [--report REPORT.json]
    symblend report BEFORE AFTER [--png PICTURE.png] [--json NUMBERS.json]
    symblend landmarks check INPUT -l LANDMARKS [--pair-table PAIRS.csv]
    symblend landmarks convert IN OUT [--specimen ID|INDEX]

The filter options are generated from the filter's parameter declaration.
Errors are one line on stderr and nothing is written; exit status 1 bad input, 2 usage, 130 interrupted.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import signal
import sys
import warnings

from .atomic import replaced_when_done, write_text
from .command_files import MESH_SAVE_FORMATS, check_loaded_mesh, check_output_path
from .errors import SymblendError, SymblendWarning
from .parameters import DEFAULTS, PARAMETERS

FRAMES = ("LPS", "RAS")


def _add_filter_options(parser: argparse.ArgumentParser) -> None:
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


def _add_landmark_options(parser: argparse.ArgumentParser, required: bool = True, note: str = "",
                          save_pair_table: bool = True) -> None:
    parser.add_argument("-l", "--landmarks", required=required, type=pathlib.Path,
                        help="landmark file: .pp, .fcsv, .mrk.json (or any markups JSON), .pts, .csv, .tps or .nts"
                             + note)
    _add_specimen_option(parser)
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
    parser.add_argument("--curve-spacing", type=_positive_length, metavar="LENGTH",
                        help="distance between semilandmarks along a curve, in mesh units; "
                             "default: 1%% of the bounding-box diagonal")
    parser.add_argument("--mesh-frame", choices=FRAMES, default="LPS",
                        help="coordinate system of the mesh, used only when the landmark file states one "
                             "(Slicer files); default: %(default)s, as Slicer saves models")
    parser.add_argument("--allow-far-landmarks", action="store_true",
                        help="snap landmarks that lie farther than 2%% of the diagonal from the surface "
                             "(without it they are an error: a wrong coordinate system or unit is likelier)")


def _add_specimen_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--specimen", metavar="ID|INDEX",
                        help="the specimen of a .tps or .nts file with several, or the markup of a Slicer markups "
                             "JSON with several (its ID, label or name, or a 1-based index); default the first, "
                             "with a warning")


def _positive_length(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive length in mesh units")
    return value


def _add_missing_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--missing", default="", metavar="NAME,NAME",
                        help="landmarks on missing or broken parts (weight 0): that side takes the "
                             "mirror shape of the other (the paper's Figure 9)")


def _one_line(error: Exception) -> str:
    return " ".join(str(error).split())


def _load_mesh(path: pathlib.Path, ms=None):
    """``path`` loaded as a new layer of ``ms`` (a new MeshSet by default), PLY attributes included."""
    import pymeshlab

    if not path.is_file():
        raise SymblendError(f"{path}: no such mesh file.")
    from .meshlab.ply_attributes import load_mesh_with_attributes

    ms = pymeshlab.MeshSet() if ms is None else ms
    try:
        load_mesh_with_attributes(ms, path)
    except pymeshlab.PyMeshLabException as error:
        raise SymblendError(f"{path}: pymeshlab cannot read it ({_one_line(error)}).") from None
    check_loaded_mesh(path, ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix())
    return ms


def _snapped_pairs(ms, args):
    from .landmarks.from_file import pairs_from_landmark_file

    left_words, _, right_words = args.side_words.lower().partition("/")
    if not left_words or not right_words:
        raise SymblendError(f"--side-words {args.side_words!r}: give LEFT,.../RIGHT,..., e.g. l,left/r,right.")
    mesh = ms.current_mesh()
    return pairs_from_landmark_file(
        mesh.vertex_matrix(), mesh.face_matrix(), args.landmarks, args.pair_table,
        (tuple(left_words.split(",")), tuple(right_words.split(","))), args.midline, args.curves,
        args.curve_spacing, args.mesh_frame, args.allow_far_landmarks, args.specimen)


def _check_outputs(args, outputs: dict[str, pathlib.Path | None], inputs: list[pathlib.Path]) -> None:
    """Every output path of the command (``{what: path or None}``) checked before any work (see
    :func:`check_output_path`); two outputs may not share a file."""
    overwrite = getattr(args, "overwrite", False)
    given = {what: path for what, path in outputs.items() if path is not None}
    for what, path in given.items():
        check_output_path(path, inputs, overwrite, what, MESH_SAVE_FORMATS if what == "output mesh" else None)
    resolved = [path.resolve() for path in given.values()]
    for index, path in enumerate(resolved):
        if path in resolved[:index]:
            raise SymblendError(f"{list(given.values())[index]}: given for two outputs; give each its own file.")


def _save_atomically(ms, output: pathlib.Path) -> None:
    """Save the current mesh to a temporary name beside ``output``, then rename it. A PLY keeps
    quality and every custom per-vertex scalar attribute."""
    import pymeshlab

    from .meshlab.attributes import custom_attribute_names

    options = {}
    if output.suffix.lower() == ".ply":
        options = {"save_vertex_quality": True,
                   **{f"__ca_vs__{name}": True for name in custom_attribute_names(ms)["vs"]}}
    try:
        with replaced_when_done(output) as temporary:
            ms.save_current_mesh(str(temporary), **options)
    except pymeshlab.PyMeshLabException as error:
        raise SymblendError(f"{output}: pymeshlab cannot write it ({_one_line(error)}).") from None


def _terminal_progress(percent: float, message: str) -> None:
    """A one-line progress display on a terminal, rewritten in place."""
    bar = "#" * int(percent / 5)
    print(f"\r[{bar:<20}] {percent:3.0f}% {message:<40}", end="\n" if percent >= 100 else "",
          file=sys.stderr, flush=True)


def _progress_display():
    return _terminal_progress if sys.stderr.isatty() else None


def _write_pair_table_for(args, pair_names, midline_names, folder: pathlib.Path) -> pathlib.Path | None:
    """Write a pair table of ``pair_names`` to --save-pair-table, else to LANDMARKS.pairs.csv in
    ``folder`` unless a file is there; its path, or None (said on stderr) when not written."""
    from .landmarks.pairing import write_pair_table

    chosen = getattr(args, "save_pair_table", None)  # a batch row writes beside its output
    path = chosen or folder / f"{args.landmarks.name.split('.')[0]}.pairs.csv"
    if chosen is None and path.exists():
        print(f"pair table not written: {path} exists (choose a file with --save-pair-table)", file=sys.stderr)
        return None
    write_pair_table(path, pair_names, midline_names)
    return path


def _geometric_pairing_note(snapped, args, folder: pathlib.Path) -> str | None:
    """When ``snapped`` was paired by geometry: print the pairing, write it as a pair table
    (:func:`_write_pair_table_for`) and return the table's path."""
    if snapped.pairing != "geometry":
        return None
    pairs = snapped.pair_names
    shown = ", ".join(f"{a}-{b}" for a, b in pairs[:30]) + (", ..." if len(pairs) > 30 else "")
    print(f"{args.landmarks}: no name carries a side; paired by geometry: {len(pairs)} pairs ({shown}); "
          f"midline: {', '.join(snapped.midline_names) or 'none'}", file=sys.stderr)
    path = _write_pair_table_for(args, pairs, snapped.midline_names, folder)
    if path:
        print(f"pair table: {path} (check or edit it, then use --pair-table {path} --midline)", file=sys.stderr)
    return str(path) if path else None


def _write_landmarks(ms, args, names: dict) -> dict:
    """Snap the landmark file onto the current mesh and store it as the attributes ``names``."""
    from .meshlab.attributes import write_landmark_attributes

    snapped = _snapped_pairs(ms, args)
    table = _geometric_pairing_note(snapped, args, args.output.parent)
    missing = [name.strip() for name in args.missing.split(",") if name.strip()]
    left_weights, right_weights = snapped.weights(missing) if missing else (None, None)
    write_landmark_attributes(ms.current_mesh(), snapped.pairs, left_weights, right_weights, names["pair_attribute"],
                              names["midline_attribute"], names["weight_attribute"])
    return {"file": str(args.landmarks), "frame": snapped.frame_note, "pairing": snapped.pairing,
            "pair_table_written": table, "pairs": [list(p) for p in snapped.pair_names],
            "midline": snapped.midline_names, "curves": snapped.curves,
            "placed_point_spacing": snapped.placed_spacing, "missing": missing,
            "snap_distance_max": float(snapped.snap_distances.max()), "left_out_unplaced": snapped.unplaced,
            "vertices": [[name, int(vertex)] for names, vertices in (
                ([a for a, _ in snapped.pair_names], snapped.pairs.left),
                ([b for _, b in snapped.pair_names], snapped.pairs.right),
                (snapped.midline_names, snapped.pairs.midline)) for name, vertex in zip(names, vertices)]}


def _write_report(path, report) -> None:
    """Write ``report`` as JSON to ``path`` (if given) under a temporary name, then rename it."""
    if path:
        write_text(path, json.dumps(report, indent=2, default=_jsonable) + "\n")


def _jsonable(value):
    import numpy as np

    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON serializable")


def symmetrize_files(args, progress=None):
    """``symblend symmetrize`` without its printout, for one parsed command line ``args``: every check,
    then the filter, the output mesh and the report written. Returns (report, the MeshSet)."""
    from .meshlab.meshset_filter import generate_symmetrized_mesh

    params = {p.name: getattr(args, p.name) for p in PARAMETERS}
    automatic = params["pairs"] == "auto"
    if automatic and (args.landmarks or args.missing):
        raise SymblendError("--pairs auto finds its own pairs; leave out -l and --missing, or use "
                            "--pairs landmarks+auto.")
    if not automatic and not args.landmarks:
        raise SymblendError("Give a landmark file (-l LANDMARKS), or --pairs auto to find pairs on the surface.")
    outputs = {"output mesh": args.output, "report": args.report, "pair table": getattr(args, "save_pair_table", None)}
    _check_outputs(args, outputs, [args.input, args.landmarks])
    ms = _load_mesh(args.input)
    landmarks = None if automatic else _write_landmarks(ms, args, params)
    if landmarks and landmarks["curves"] and not params["width_spacing"]:
        params["width_spacing"] = landmarks["placed_point_spacing"]  # semilandmarks leave the widths as they were
    report = generate_symmetrized_mesh(ms, progress, **params)
    report["landmarks"] = landmarks
    _save_atomically(ms, args.output)
    _write_report(args.report, report)
    return report, ms


def _symmetrize(args) -> int:
    report, _ = symmetrize_files(args, _progress_display())
    pairs = f"{report['pair_count']} landmark pairs"
    if "auto_pairs" in report:
        automatic_pairs = report["auto_pairs"]
        pairs += (f" + {automatic_pairs['pair_count']} automatic pairs ({len(automatic_pairs['rounds'])} rounds, "
                  f"stopped: {automatic_pairs['stopped']})")
    landmark_line = ""
    if "landmark_asymmetry_before" in report:
        before, after = report["landmark_asymmetry_before"], report["landmark_asymmetry_after"]
        landmark_line = (f"landmark asymmetry RMS {before['rms_relative']:.2%} -> {after['rms_relative']:.1e} "
                         "of the diagonal; ")
    checks = ""
    if "mirror_asymmetry_before" in report:
        before, after = report["mirror_asymmetry_before"], report["mirror_asymmetry_after"]
        checks = ("mirror asymmetry of the diagonal, before -> after: " + ", ".join(
            f"{label} {before[key + '_relative']:.3%} -> {after[key + '_relative']:.3%}"
            for label, key in (("median", "p50"), ("p90", "p90"), ("RMS", "rms"))))
    if "hausdorff_input_output" in report:
        checks += f"; two-way Hausdorff input<->output {report['hausdorff_input_output']['max']:.4g}"
    print(f"{args.output}: {pairs}, mode {report['mode']}; {landmark_line}{checks}".rstrip("; "))
    for message in report.get("warnings", []):
        print(f"warning: {message}", file=sys.stderr)
    return 0


def _mlx(args) -> int:
    from .meshlab.mlx import read_filter_script, symblend_options
    from .meshlab.script_runner import apply_filter_script

    _check_outputs(args, {"output mesh": args.output, "report": args.report, "pair table": args.save_pair_table},
                   [args.input, args.script, args.landmarks])
    ours = [symblend_options(node, args.script) for node in read_filter_script(args.script) if node.is_symblend]
    needs_landmarks = [options for options in ours if options["pairs"] != "auto"]
    if needs_landmarks and not args.landmarks:
        raise SymblendError(f"{args.script} runs the filter with pairs='{needs_landmarks[0]['pairs']}'; give the "
                            "landmark file with -l LANDMARKS (or use a script whose pairs are 'auto').")
    ms = _load_mesh(args.input)
    landmarks = None
    if args.landmarks:
        options = ours[0] if ours else DEFAULTS
        landmarks = _write_landmarks(ms, args, options)
        if landmarks["curves"] and not options["width_spacing"]:
            warnings.warn(f"{args.script} has width_spacing 0, so its widths are multiples of the semilandmark "
                          f"spacing; set width_spacing to {landmarks['placed_point_spacing']:.4g} (the spacing of "
                          "the placed points) in the script to keep them as without curves.", SymblendWarning)
    steps = apply_filter_script(ms, args.script, _progress_display())
    for number, step in enumerate(steps, start=1):
        if "translated" in step:
            print(f"{args.script}, filter {number}: {step['translated']}", file=sys.stderr)
    _save_atomically(ms, args.output)
    _write_report(args.report, {"script": str(args.script), "landmarks": landmarks, "steps": steps})
    print(f"{args.output}: {len(steps)} filters of {args.script} applied")
    return 0


def _batch(args) -> int:
    from .batch import OUTPUT_OPTIONS, run

    if args.workers is not None and args.workers < 1:
        raise SymblendError(f"--workers {args.workers}: give 1 or more processes.")
    defaults = []  # the options given on the command line, as words of symblend symmetrize
    for action in args.parser._actions:
        if not action.option_strings or action.dest in (*OUTPUT_OPTIONS, "manifest", "workers", "scheduler", "force"):
            continue
        value = getattr(args, action.dest)
        if value == action.default or value is None:
            continue
        defaults += [action.option_strings[-1]] if action.nargs == 0 else [action.option_strings[-1], str(value)]
    summaries = run(args.manifest, args.output, defaults, args.workers, args.scheduler, args.force,
                    progress=sys.stderr.isatty())
    failed = [s for s in summaries if s["status"] == "failed"]
    print(f"{args.output}: {len(summaries) - len(failed)} of {len(summaries)} specimens symmetrized"
          + (f", {sum(s['status'] == 'done before' for s in summaries)} of them done before" if not args.force else "")
          + (f"; {len(failed)} failed (see summary.csv)" if failed else ""))
    return 1 if failed else 0


def _report(args) -> int:
    from .checks.comparison import compare_layers
    from .core.mirror_fill import distances_to_surface
    from .checks.surface_asymmetry import CHECK_SAMPLES
    from .checks.verdict import result_warnings

    outputs = {"picture": args.png, "JSON report": args.json, "distance mesh": args.distance_ply}
    _check_outputs(args, outputs, [args.before, args.after])
    ms = _load_mesh(args.before)
    before_id = ms.current_mesh_id()
    after_id = _load_mesh(args.after, ms).current_mesh_id()
    # The picture colours every vertex; the numbers alone need a sample.
    result = compare_layers(ms, before_id, after_id, None if args.png else CHECK_SAMPLES)
    before, after = result["mirror_asymmetry_before"], result["mirror_asymmetry_after"]
    hausdorff = result["hausdorff_before_after"]
    keys = ("max", "mean", "rms", "p50", "p90", "p99")
    print(f"{'(mesh units)':24}" + "".join(f"{k:>11}" for k in keys))
    print(f"{'Hausdorff before<->after':24}" + "".join(f"{hausdorff[k]:11.4g}" for k in keys))
    for label, measured in (("mirror asymmetry before", before), ("mirror asymmetry after", after)):
        print(f"{label:24}" + "".join(f"{measured[k]:11.4g}" for k in keys))
    print(f"{'(% of the diagonal)':24}" + "".join(f"{k:>11}" for k in keys))
    for label, measured in (("mirror asymmetry before", before), ("mirror asymmetry after", after)):
        print(f"{label:24}" + "".join(f"{100 * measured[k + '_relative']:11.4g}" for k in keys))
    result["warnings"] = result_warnings(before, after, hausdorff, ms.mesh(before_id).bounding_box().diagonal())
    for message in result["warnings"]:
        print(f"warning: {message}", file=sys.stderr)
    before_mesh, after_mesh = ms.mesh(before_id), ms.mesh(after_id)
    if args.per_vertex or args.distance_ply:  # one direction of the Hausdorff distance, every vertex
        after_to_before = distances_to_surface(before_mesh.vertex_matrix(), before_mesh.face_matrix(),
                                               after_mesh.vertex_matrix())
    if args.per_vertex:
        result["hausdorff_per_vertex"] = {
            "before_to_after": distances_to_surface(after_mesh.vertex_matrix(), after_mesh.face_matrix(),
                                                    before_mesh.vertex_matrix()),
            "after_to_before": after_to_before}
    if args.distance_ply:
        ms.set_current_mesh(after_id)
        _save_quality_ply(ms, args.distance_ply, after_to_before)
        print(f"distance mesh: {args.distance_ply} (quality: each vertex's distance to the mesh before)")
    if args.png:
        from .checks.render import render_comparison

        meshes = [dict(result[key], points=ms.mesh(mesh_id).vertex_matrix(), faces=ms.mesh(mesh_id).face_matrix())
                  for key, mesh_id in (("mirror_asymmetry_before", before_id), ("mirror_asymmetry_after", after_id))]
        result["png_views"] = render_comparison(args.png, *meshes, titles=(args.before.name, args.after.name))
        print(f"picture: {args.png}")
    _write_report(args.json, result)
    return 0


def _save_quality_ply(ms, path: pathlib.Path, quality) -> None:
    """Save the current mesh of ``ms`` to ``path`` with ``quality`` (N,) as its per-vertex quality."""
    import numpy as np
    import pymeshlab

    mesh = ms.current_mesh()
    copy = pymeshlab.Mesh(mesh.vertex_matrix(), mesh.face_matrix(), v_scalar_array=np.asarray(quality, dtype=float))
    scratch = pymeshlab.MeshSet()
    scratch.add_mesh(copy)
    _save_atomically(scratch, path)


def _check(args) -> int:
    from .core.landmark_pairs import check_pairs

    from .landmarks.from_file import AmbiguousPairingError

    _check_outputs(args, {"pair table": args.save_pair_table}, [args.input, args.landmarks])
    ms = _load_mesh(args.input)
    try:
        snapped = _snapped_pairs(ms, args)
    except AmbiguousPairingError as error:
        path = _write_pair_table_for(args, error.pair_names, error.midline_names, args.landmarks.parent)
        if path is None:
            raise
        raise SymblendError(f"{error.problem} The {len(error.pair_names)} pairs found are in {path}: add the "
                            f"ambiguous ones, then use --pair-table {path} --midline.") from None
    _geometric_pairing_note(snapped, args, args.landmarks.parent)
    print(f"{args.landmarks}: {snapped.frame_note}; paired by {snapped.pairing}: {len(snapped.pair_names)} pairs, "
          f"{len(snapped.midline_names)} midline")
    for k, ((left, right), distance) in enumerate(zip(snapped.pair_names, snapped.snap_distances), start=1):
        print(f"  {k:3d}  {left} -> vertex {snapped.pairs.left[k - 1]} (snap {distance[0]:.3g})   "
              f"{right} -> vertex {snapped.pairs.right[k - 1]} (snap {distance[1]:.3g})")
    if snapped.midline_names:
        print(f"midline: {', '.join(snapped.midline_names)}")
    for curve in snapped.curves:
        print(f"curve {curve['name']}{' (midline)' if curve['midline'] else ''}: "
              f"{'/'.join(map(str, curve['control_points']))} control points, surface length "
              f"{'/'.join(f'{x:.4g}' for x in curve['surface_length'])}, {curve['samples']} semilandmarks"
              + (f" ({curve['dropped_on_used_vertices']} dropped on vertices already used)"
                 if curve['dropped_on_used_vertices'] else ""))
    if snapped.unplaced:
        print(f"left out (not placed): {', '.join(snapped.unplaced)}")
    check_pairs(ms.current_mesh().vertex_matrix(), snapped.pairs)
    print("ok: the pairs can be symmetrized")
    return 0


def _convert(args) -> int:
    from .landmarks.files import read_landmarks, write_landmarks

    _check_outputs(args, {"landmark file": args.output}, [args.input])
    write_landmarks(args.output, read_landmarks(args.input, args.specimen))
    print(f"{args.input} -> {args.output}")
    return 0


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line usage error (exit status 2) that points to ``--help``."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see: {self.prog} --help)\n")


class _RaisingParser(_Parser):
    """The same options, whose usage errors raise SymblendError (a batch row's options)."""

    def error(self, message: str):
        raise SymblendError(message)


def symmetrize_arguments(argv: list[str]) -> argparse.Namespace:
    """``argv`` (the words after ``symblend symmetrize``) parsed as that command does; bad options raise
    SymblendError."""
    parser = _RaisingParser(prog="symblend symmetrize")
    _add_symmetrize_arguments(parser)
    return parser.parse_args(argv)


def _add_symmetrize_arguments(run: argparse.ArgumentParser) -> None:
    run.add_argument("input", type=pathlib.Path, help="mesh file (any format pymeshlab reads)")
    _add_landmark_options(run, required=False, note=" (not with --pairs auto)")
    run.add_argument("-o", "--output", required=True, type=pathlib.Path,
                     help="output mesh; .ply keeps quality (local asymmetry) and the attributes")
    run.add_argument("--report", type=pathlib.Path, help="write the filter's report as JSON")
    run.add_argument("--overwrite", action="store_true", help="allow -o to name the input mesh (replaced at the end)")
    _add_missing_option(run)
    _add_filter_options(run)


def build_parser() -> argparse.ArgumentParser:
    from importlib.metadata import PackageNotFoundError, version

    try:
        installed = version("filter-symblend")
    except PackageNotFoundError:
        installed = "unknown (not installed)"
    parser = _Parser(prog="symblend", description=__doc__.split("\n\n")[0])
    parser.add_argument("--version", action="version", version=f"symblend (filter-symblend) {installed}")
    commands = parser.add_subparsers(dest="command", required=True)
    run = commands.add_parser("symmetrize", help="symmetrize a mesh from landmark pairs or automatic pairs")
    _add_symmetrize_arguments(run)
    run.set_defaults(handler=_symmetrize)

    batch = commands.add_parser("batch", help="symmetrize every specimen of a manifest CSV (a study), locally or "
                                              "on a Dask cluster")
    batch.add_argument("manifest", type=pathlib.Path,
                       help="CSV with a header: mesh, optionally landmarks and any symmetrize option per row")
    batch.add_argument("-o", "--output", required=True, type=pathlib.Path, metavar="OUTDIR",
                       help="folder for <mesh stem>.ply/.json, summary.csv and landmarks.tps")
    batch.add_argument("--workers", type=int, default=None, metavar="N",
                       help="local processes (default: the cores), BLAS at one thread each")
    batch.add_argument("--scheduler", metavar="ADDRESS",
                       help="run on the Dask cluster at ADDRESS (tcp://host:8786); needs filter-symblend[cluster]")
    batch.add_argument("--force", action="store_true", help="redo rows whose outputs are newer than their inputs")
    _add_landmark_options(batch, required=False, note=" (default for rows without a landmarks column)",
                          save_pair_table=False)
    _add_missing_option(batch)
    _add_filter_options(batch)
    batch.set_defaults(handler=_batch, parser=batch)

    script = commands.add_parser("mlx", help="run a MeshLab filter script (.mlx) that may use our filter")
    script.add_argument("script", type=pathlib.Path, help="filter script (.mlx), e.g. one of mlx_presets/")
    script.add_argument("input", type=pathlib.Path, help="mesh file (any format pymeshlab reads)")
    _add_landmark_options(script, required=False, note=" (for scripts whose filter uses landmarks)")
    _add_missing_option(script)
    script.add_argument("-o", "--output", required=True, type=pathlib.Path,
                        help="the current mesh after the script; .ply keeps quality and the attributes")
    script.add_argument("--report", type=pathlib.Path, help="write every filter's output as JSON")
    script.add_argument("--overwrite", action="store_true", help="allow -o to name the input mesh (replaced at the end)")
    script.set_defaults(handler=_mlx)

    report = commands.add_parser("report", help="before/after check: Hausdorff and mirror asymmetry")
    report.add_argument("before", type=pathlib.Path, help="mesh before symmetrizing")
    report.add_argument("after", type=pathlib.Path, help="mesh after symmetrizing")
    report.add_argument("--png", type=pathlib.Path,
                        help="picture of both meshes coloured by mirror asymmetry (needs matplotlib)")
    report.add_argument("--json", type=pathlib.Path, help="write the numbers as JSON")
    report.add_argument("--per-vertex", action="store_true",
                        help="add each vertex's Hausdorff distance (before -> after and after -> before) to the JSON")
    report.add_argument("--distance-ply", type=pathlib.Path, metavar="MESH.ply",
                        help="write the mesh after with each vertex's distance to the mesh before as its quality "
                             "(MeshLab colours it with Colorize by vertex Quality)")
    report.set_defaults(handler=_report)

    landmarks = commands.add_parser("landmarks", help="check or convert landmark files")
    sub = landmarks.add_subparsers(dest="landmarks_command", required=True)
    check = sub.add_parser("check", help="list pairs and snap distances; report problems")
    check.add_argument("input", type=pathlib.Path, help="mesh file")
    _add_landmark_options(check)
    check.set_defaults(handler=_check)
    convert = sub.add_parser("convert", help="convert between .pp, .fcsv, .mrk.json, .pts, .csv, .tps, .nts")
    convert.add_argument("input", type=pathlib.Path)
    convert.add_argument("output", type=pathlib.Path)
    _add_specimen_option(convert)
    convert.set_defaults(handler=_convert)
    return parser


def _show_warning(message, category, *rest) -> None:
    print(f"symblend: warning: {_one_line(message)}", file=sys.stderr)


def main(argv=None) -> int:
    """Exit status: 0 done, 1 bad input (one line on stderr, nothing written), 2 usage, 130 interrupted."""
    signal.signal(signal.SIGINT, signal.default_int_handler)  # start-up is over: Ctrl-C is KeyboardInterrupt
    try:
        args = build_parser().parse_args(argv)
        with warnings.catch_warnings():
            # numpy/scipy warnings are expected where results are checked (the core raises on any
            # non-finite output); ours name a cause and a fix.
            warnings.simplefilter("ignore")
            warnings.simplefilter("always", SymblendWarning)
            warnings.showwarning = _show_warning
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
