"""``symblend pairs INPUT -o PAIRS``: the automatic pairs written as landmark pairs a person can check,
move or delete in MeshLab's PickPoints or in Slicer, then give back to ``symblend symmetrize -l``."""

from __future__ import annotations

import pathlib
import sys

from ..api import find_mirror_pairs
from ..core.mirror_pairs import pairs_to_check
from ..errors import SymblendError
from ..landmarks.formats import Landmark, LandmarkSet, write_landmarks
from ..parameters import ARRAYS, PARAMETERS, options_of
from .shared.console import progress_display
from .shared.landmark_input import snapped_pairs
from .shared.mesh_io import check_outputs, load_mesh
from .shared.options import add_filter_options, add_landmark_options

DEFAULT_COUNT = 20  # pairs a person checks by eye in a few minutes
WRITABLE = (".pp", ".fcsv", ".mrk.json", ".csv")  # formats that `symmetrize -l` reads back with their names


def register(commands) -> None:
    """Add the command to ``commands`` (argparse subparsers)."""
    parser = commands.add_parser(
        "pairs", help="find automatic pairs and write them as landmark pairs to check and correct",
        description="Find the mirror map of the mesh as --pairs auto does and write COUNT of its confident pairs, "
                    "spread over the surface, as landmark pairs (L_auto_1 / R_auto_1, ...). Check them in MeshLab's "
                    "PickPoints (.pp) or in Slicer (.fcsv, .mrk.json), move or delete the wrong ones, then run "
                    "symblend symmetrize INPUT -l PAIRS. With -l, your landmarks are kept (landmarks+auto) and "
                    "written first.")
    parser.add_argument("input", type=pathlib.Path, help="mesh file (any format pymeshlab reads)")
    parser.add_argument("-o", "--output", required=True, type=pathlib.Path,
                        help=f"landmark file to write, its format by its extension: {', '.join(WRITABLE)}")
    parser.add_argument("--count", type=int, default=DEFAULT_COUNT, metavar="N",
                        help="how many pairs to write, spread evenly over the confident ones; default %(default)s")
    parser.add_argument("--overwrite", action="store_true", help="allow -o to replace an existing landmark file")
    add_landmark_options(parser, required=False, note=" (optional: kept, and the automatic pairs added)",
                         save_pair_table=False)
    add_filter_options(parser)
    parser.set_defaults(handler=run, pairs=None)
    pairs = next(action for action in parser._actions if action.dest == "pairs")
    pairs.help = "where the pairs come from: auto, or landmarks+auto with -l; default: auto (landmarks+auto with -l)"


def run(args) -> int:
    """The command: the map found, the pairs chosen and written, one line on stdout."""
    if not args.output.name.lower().endswith(WRITABLE):
        raise SymblendError(f"{args.output}: write the pairs as {', '.join(WRITABLE)} (symblend symmetrize -l reads "
                            "them back by their names).")
    if args.count < 1:
        raise SymblendError(f"--count {args.count}: give at least 1 pair to write.")
    check_outputs(args, {"landmark file": args.output}, [args.input, args.landmarks])
    if args.output.exists() and not args.overwrite:
        raise SymblendError(f"{args.output}: exists (pairs you corrected, perhaps); choose another file, or add "
                            "--overwrite to replace it.")
    ms = load_mesh(args.input)
    mesh = ms.current_mesh()
    points, faces = mesh.vertex_matrix(), mesh.face_matrix()
    params = options_of({p.name: getattr(args, p.name) for p in PARAMETERS}, ARRAYS)
    landmarks, kept = {}, []
    if args.landmarks:
        snapped = snapped_pairs(ms, args)
        landmarks = dict(left=snapped.pairs.left, right=snapped.pairs.right, midline=snapped.pairs.midline)
        kept = [Landmark(name, tuple(points[vertex])) for names, vertices in (
            ([a for a, _ in snapped.pair_names], snapped.pairs.left),
            ([b for _, b in snapped.pair_names], snapped.pairs.right),
            (snapped.midline_names, snapped.pairs.midline)) for name, vertex in zip(names, vertices)]
    params["pairs"] = args.pairs or ("landmarks+auto" if args.landmarks else "auto")
    pairs = find_mirror_pairs(points, faces if len(faces) else None, progress=progress_display(), **landmarks,
                              **params)
    rows = pairs_to_check(pairs, points, args.count)
    automatic = []
    for k, row in enumerate(rows, start=1):
        automatic += [Landmark(f"L_auto_{k}", tuple(points[pairs.vertex[row]])),
                      Landmark(f"R_auto_{k}", tuple(pairs.twin[row]))]
    write_landmarks(args.output, LandmarkSet(kept + automatic))
    report = pairs.report
    print(f"{args.output}: {len(rows)} automatic pairs (of {int(pairs.confident().sum())} confident twins; map: "
          f"{report.map}; {report.confident_share:.0%} of the surface has a confident twin, "
          f"{report.coverage:.0%} a twin){' and your ' + str(len(kept)) + ' landmarks' if kept else ''}")
    if report.alternatives:
        others = ", ".join(report.alternatives)
        print(f"symblend: warning: other symmetries mirror this shape about as well ({others}): these pairs follow "
              f"{report.map}, whatever their confidence; keep them, or move them to the symmetry you mean, and "
              f"symmetrize with -l {args.output}.", file=sys.stderr)
    elif len(rows) < args.count:
        print(f"symblend: warning: only {len(rows)} confident pairs lie apart from the midline; place landmarks "
              "where the map is not sure (symblend symmetrize --pairs auto writes the per-vertex confidence "
              "as symblend_pair_confidence).", file=sys.stderr)
    return 0
