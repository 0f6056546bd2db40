"""A landmark file given to the ``symblend`` command, snapped onto the loaded mesh: paired (by name, by a
pair table or by geometry, said on stderr and written as a pair table to check), then handed to the filter
as pairs (``symblend symmetrize``) or stored as its attributes for a filter script (``symblend mlx``)."""

from __future__ import annotations

import dataclasses
import pathlib
import sys

from ...core.landmark_pairs import LandmarkPairs
from ...errors import SymblendError
from ...landmarks.from_file import pairs_from_landmark_file
from ...landmarks.pairing import write_pair_table
from ...meshlab.attributes import write_landmark_attributes


def snapped_pairs(ms, args):
    """The landmark file of ``args`` snapped onto the current mesh of ``ms`` and paired (SnappedPairs)."""
    left_words, _, right_words = args.side_words.lower().partition("/")
    if not left_words or not right_words:
        raise SymblendError(f"--side-words {args.side_words!r}: give LEFT,.../RIGHT,..., e.g. l,left/r,right.")
    mesh = ms.current_mesh()
    return pairs_from_landmark_file(
        mesh.vertex_matrix(), mesh.face_matrix(), args.landmarks, args.pair_table,
        (tuple(left_words.split(",")), tuple(right_words.split(","))), args.midline, args.curves,
        args.curve_spacing, args.mesh_frame, args.allow_far_landmarks, args.specimen)


def write_pair_table_for(args, pair_names, midline_names, folder: pathlib.Path) -> pathlib.Path | None:
    """Write a pair table of ``pair_names`` to --save-pair-table, else to LANDMARKS.pairs.csv in
    ``folder`` unless a file is there; its path, or None (said on stderr) when not written."""
    chosen = getattr(args, "save_pair_table", None)  # a batch row writes beside its output
    path = chosen or folder / f"{args.landmarks.name.split('.')[0]}.pairs.csv"
    if chosen is None and path.exists():
        print(f"pair table not written: {path} exists (choose a file with --save-pair-table)", file=sys.stderr)
        return None
    write_pair_table(path, pair_names, midline_names)
    return path


def geometric_pairing_note(snapped, args, folder: pathlib.Path) -> str | None:
    """When ``snapped`` was paired by geometry: print the pairing, write it as a pair table
    (:func:`write_pair_table_for`) and return the table's path."""
    if snapped.pairing != "geometry":
        return None
    pairs = snapped.pair_names
    shown = ", ".join(f"{a}-{b}" for a, b in pairs[:30]) + (", ..." if len(pairs) > 30 else "")
    print(f"{args.landmarks}: no name carries a side; paired by geometry: {len(pairs)} pairs ({shown}); "
          f"midline: {', '.join(snapped.midline_names) or 'none'}", file=sys.stderr)
    path = write_pair_table_for(args, pairs, snapped.midline_names, folder)
    if path:
        print(f"pair table: {path} (check or edit it, then use --pair-table {path} --midline)", file=sys.stderr)
    return str(path) if path else None


def read_landmarks(ms, args) -> tuple[LandmarkPairs, dict]:
    """The landmark file of ``args`` snapped onto the current mesh of ``ms`` and paired, with the weights
    of ``--missing`` (0 for the landmarks it names), and what the report records of it (names, pairing,
    snap distances, each landmark's vertex)."""
    snapped = snapped_pairs(ms, args)
    table = geometric_pairing_note(snapped, args, args.output.parent)
    missing = [name.strip() for name in args.missing.split(",") if name.strip()]
    pairs = snapped.pairs
    if missing:
        left_weights, right_weights = snapped.weights(missing)
        pairs = dataclasses.replace(pairs, left_weights=left_weights, right_weights=right_weights)
    record = {"file": str(args.landmarks), "frame": snapped.frame_note, "pairing": snapped.pairing,
              "pair_table_written": table, "pairs": [list(p) for p in snapped.pair_names],
              "midline": snapped.midline_names, "curves": snapped.curves,
              "placed_point_spacing": snapped.placed_spacing, "missing": missing,
              "snap_distance_max": float(snapped.snap_distances.max()), "left_out_unplaced": snapped.unplaced,
              "vertices": [[name, int(vertex)] for names, vertices in (
                  ([a for a, _ in snapped.pair_names], snapped.pairs.left),
                  ([b for _, b in snapped.pair_names], snapped.pairs.right),
                  (snapped.midline_names, snapped.pairs.midline)) for name, vertex in zip(names, vertices)]}
    return pairs, record


def write_landmarks(ms, args, names: dict) -> dict:
    """:func:`read_landmarks`, stored as the attributes ``names`` of the current mesh (for a filter script,
    whose node reads them); the record."""
    pairs, record = read_landmarks(ms, args)
    write_landmark_attributes(ms.current_mesh(), pairs, *((pairs.left_weights, pairs.right_weights)
                                                           if pairs.is_weighted() else (None, None)),
                              names["pair_attribute"], names["midline_attribute"], names["weight_attribute"])
    return record
