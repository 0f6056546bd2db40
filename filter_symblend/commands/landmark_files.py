"""``symblend landmarks check INPUT -l LANDMARKS`` and ``symblend landmarks convert IN OUT``: a landmark
file's pairs listed and checked against the mesh, and landmark files converted between formats."""

from __future__ import annotations

import pathlib

from ..core.landmark_pairs import check_pairs
from ..errors import SymblendError
from ..landmarks.formats import read_landmarks, write_landmarks
from ..landmarks.from_file import AmbiguousPairingError
from .shared.landmark_input import geometric_pairing_note, snapped_pairs, write_pair_table_for
from .shared.mesh_io import check_outputs, load_mesh
from .shared.options import add_landmark_options, add_specimen_option


def register(commands) -> None:
    """Add the two commands under ``landmarks`` to ``commands`` (argparse subparsers)."""
    landmarks = commands.add_parser("landmarks", help="check or convert landmark files")
    sub = landmarks.add_subparsers(dest="landmarks_command", required=True)
    check = sub.add_parser("check", help="list pairs and snap distances; report problems")
    check.add_argument("input", type=pathlib.Path, help="mesh file")
    add_landmark_options(check)
    check.set_defaults(handler=run_check)
    convert = sub.add_parser("convert", help="convert between .pp, .fcsv, .mrk.json, .pts, .csv, .tps, .nts")
    convert.add_argument("input", type=pathlib.Path)
    convert.add_argument("output", type=pathlib.Path)
    add_specimen_option(convert)
    convert.set_defaults(handler=run_convert)


def run_check(args) -> int:
    """``landmarks check``: each pair's vertices and snap distances, then the warp's own checks of the pairs."""
    check_outputs(args, {"pair table": args.save_pair_table}, [args.input, args.landmarks])
    ms = load_mesh(args.input)
    try:
        snapped = snapped_pairs(ms, args)
    except AmbiguousPairingError as error:
        path = write_pair_table_for(args, error.pair_names, error.midline_names, args.landmarks.parent)
        if path is None:
            raise
        raise SymblendError(f"{error.problem} The {len(error.pair_names)} pairs found are in {path}: add the "
                            f"ambiguous ones, then use --pair-table {path} --midline.") from None
    geometric_pairing_note(snapped, args, args.landmarks.parent)
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


def run_convert(args) -> int:
    """``landmarks convert``: the landmark file read in one format and written in another."""
    check_outputs(args, {"landmark file": args.output}, [args.input])
    write_landmarks(args.output, read_landmarks(args.input, args.specimen))
    print(f"{args.input} -> {args.output}")
    return 0
