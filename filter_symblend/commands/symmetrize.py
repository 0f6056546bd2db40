"""``symblend symmetrize INPUT (-l LANDMARKS | --pairs auto) -o OUTPUT``: one mesh, from a landmark file
or from automatic pairs, through the MeshSet filter; the output mesh and the JSON report written."""

from __future__ import annotations

import sys

from ..errors import SymblendError
from ..meshlab.meshset_filter import generate_symmetrized_mesh
from ..parameters import PARAMETERS
from .console import progress_display
from .landmark_input import write_landmarks
from .mesh_io import check_outputs, load_mesh, save_with_report
from .options import add_symmetrize_arguments


POINTS_ONLY = (".xyz",)  # mesh formats pymeshlab writes without faces


def register(commands) -> None:
    """Add the command to ``commands`` (argparse subparsers)."""
    parser = commands.add_parser("symmetrize", help="symmetrize a mesh from landmark pairs or automatic pairs")
    add_symmetrize_arguments(parser)
    parser.set_defaults(handler=run)


def symmetrize_files(args, progress=None):
    """``symblend symmetrize`` without its printout, for one parsed command line ``args``: every check,
    then the filter, the output mesh and the report written. Returns (report, the MeshSet)."""
    params = {p.name: getattr(args, p.name) for p in PARAMETERS}
    automatic = params["pairs"] == "auto"
    if automatic and (args.landmarks or args.missing):
        raise SymblendError("--pairs auto finds its own pairs; leave out -l and --missing, or use "
                            "--pairs landmarks+auto.")
    if not automatic and not args.landmarks:
        raise SymblendError("Give a landmark file (-l LANDMARKS), or --pairs auto to find pairs on the surface.")
    outputs = {"output mesh": args.output, "report": args.report, "pair table": getattr(args, "save_pair_table", None)}
    check_outputs(args, outputs, [args.input, args.landmarks])
    ms = load_mesh(args.input)
    if args.output.suffix.lower() in POINTS_ONLY and not ms.current_mesh().is_point_cloud():
        raise SymblendError(f"{args.output}: a {args.output.suffix} file holds points only, and {args.input} has faces: "
                            "they would be lost with the per-vertex asymmetry; write .ply (or .obj, .off for the "
                            "faces alone).")
    landmarks = None if automatic else write_landmarks(ms, args, params)
    if landmarks and landmarks["curves"] and not params["width_spacing"]:
        params["width_spacing"] = landmarks["placed_point_spacing"]  # semilandmarks leave the widths as they were
    report = generate_symmetrized_mesh(ms, progress, **params)
    report["landmarks"] = landmarks
    save_with_report(ms, args.output, args.report, report)
    return report, ms


def run(args) -> int:
    """The command: :func:`symmetrize_files`, then one line of figures on stdout and the warnings on stderr."""
    report, _ = symmetrize_files(args, progress_display())
    pairs = f"{report['pair_count']} landmark pairs"
    if "auto_pairs" in report:
        automatic_pairs = report["auto_pairs"]
        pairs += (f" + {automatic_pairs['pair_count']} automatic pairs ({len(automatic_pairs['rounds'])} rounds, "
                  f"stopped: {automatic_pairs['stopped']}; confident twins on "
                  f"{automatic_pairs['mirror_map']['confident_share']:.0%} of the surface)")
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
    if "uncertainty" in report:
        print(uncertainty_line(report["uncertainty"], report.get("landmarks")))
    for message in report.get("warnings", []):
        print(f"warning: {message}", file=sys.stderr)
    return 0


def landmark_name(unit: str, landmarks: dict | None) -> str:
    """The file's names for a pair id or ``midline k`` of the filter's report (the id when not from a file)."""
    if not landmarks:
        return f"pair {unit}" if unit.isdigit() else unit
    if unit.isdigit():
        return "/".join(landmarks["pairs"][int(unit) - 1])
    return landmarks["midline"][int(unit.split()[-1]) - 1]


def uncertainty_line(uncertainty: dict, landmarks: dict | None) -> str:
    """One line of the report's ``uncertainty``, the most influential pair by its landmark names."""
    top = uncertainty["most_influential_pair"]
    return (f"uncertainty (jackknife, {uncertainty['left_out']} landmarks left out in turn): median "
            f"{uncertainty['median_relative']:.3%}, p90 {uncertainty['p90_relative']:.3%}, max "
            f"{uncertainty['max_relative']:.3%} of the diagonal; most influential: {landmark_name(top, landmarks)} "
            f"(the result moves up to {uncertainty['influence_relative'][top]:.3%} without it)")
