"""``symblend report BEFORE AFTER``: the before/after check of two meshes, the two-way Hausdorff distance
and the mirror asymmetry of each, as a table, JSON, a picture or a distance mesh."""

from __future__ import annotations

import pathlib
import sys

import numpy as np

from ..atomic import all_or_none
from ..core.mirror_fill import distances_to_surface
from ..measures.surface_asymmetry import CHECK_SAMPLES
from ..measures.verdict import result_warnings
from ..meshlab.attributes import optional_attribute
from ..meshlab.layer_checks import compare_layers
from ..meshlab.meshset_filter import UNCERTAINTY_ATTRIBUTE
from .shared.mesh_io import check_outputs, load_mesh, report_json, save_quality_ply


def register(commands) -> None:
    """Add the command to ``commands`` (argparse subparsers)."""
    report = commands.add_parser("report", help="before/after check: Hausdorff and mirror asymmetry")
    report.add_argument("before", type=pathlib.Path, help="mesh before symmetrizing")
    report.add_argument("after", type=pathlib.Path, help="mesh after symmetrizing")
    report.add_argument("--png", type=pathlib.Path,
                        help="picture of both meshes coloured by mirror asymmetry, and of the output by its "
                             "uncertainty when it has one (symblend_uncertainty; needs matplotlib)")
    report.add_argument("--json", type=pathlib.Path, help="write the numbers as JSON")
    report.add_argument("--per-vertex", action="store_true",
                        help="add each vertex's Hausdorff distance (before -> after and after -> before) to the JSON")
    report.add_argument("--distance-ply", type=pathlib.Path, metavar="MESH.ply",
                        help="write the mesh after with each vertex's distance to the mesh before as its quality "
                             "(MeshLab colours it with Colorize by vertex Quality)")
    report.set_defaults(handler=run)



def run(args) -> int:
    """The command: the table on stdout, then the JSON, the distance mesh and the picture that were asked for,
    all of them or none."""
    outputs = {"picture": args.png, "JSON report": args.json, "distance mesh": args.distance_ply}
    check_outputs(args, outputs, [args.before, args.after])
    ms = load_mesh(args.before)
    before_id = ms.current_mesh_id()
    after_id = load_mesh(args.after, ms).current_mesh_id()
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
    with all_or_none([args.distance_ply, args.png, args.json]) as (distance_file, picture_file, json_file):
        if args.distance_ply:
            ms.set_current_mesh(after_id)
            save_quality_ply(ms, distance_file, after_to_before, args.distance_ply)
        if args.png:
            from ..measures.render import render_comparison  # matplotlib, only for --png

            meshes = [dict(result[key], points=ms.mesh(mesh_id).vertex_matrix(), faces=ms.mesh(mesh_id).face_matrix())
                      for key, mesh_id in (("mirror_asymmetry_before", before_id), ("mirror_asymmetry_after", after_id))]
            spread = optional_attribute(after_mesh, UNCERTAINTY_ATTRIBUTE)  # an output with uncertainty shows it
            uncertainty = None if spread is None else {
                "per_vertex": spread, "p90_relative": float(np.percentile(spread, 90)) / before_mesh.bounding_box().diagonal()}
            result["png_views"] = render_comparison(picture_file, *meshes, titles=(args.before.name, args.after.name),
                                                    uncertainty=uncertainty)
        if args.json:
            json_file.write_text(report_json(result), encoding="utf-8")
    if args.distance_ply:
        print(f"distance mesh: {args.distance_ply} (quality: each vertex's distance to the mesh before)")
    if args.png:
        print(f"picture: {args.png}")
    return 0
