"""``symblend mlx SCRIPT.mlx INPUT [-l LANDMARKS] -o OUTPUT``: a MeshLab filter script run on one mesh,
our filter's steps included (their landmarks from the file)."""

from __future__ import annotations

import pathlib
import sys
import warnings

from ..errors import SymblendError, SymblendWarning
from ..meshlab.filter_script import read_filter_script, symblend_options
from ..meshlab.script_runner import apply_filter_script
from ..parameters import DEFAULTS
from .shared.console import progress_display
from .shared.landmark_input import write_landmarks
from .shared.mesh_io import check_outputs, load_mesh, save_with_report
from .shared.options import add_landmark_options, add_missing_option


def register(commands) -> None:
    """Add the command to ``commands`` (argparse subparsers)."""
    script = commands.add_parser("mlx", help="run a MeshLab filter script (.mlx) that may use our filter")
    script.add_argument("script", type=pathlib.Path, help="filter script (.mlx), e.g. one of mlx_presets/")
    script.add_argument("input", type=pathlib.Path, help="mesh file (any format pymeshlab reads)")
    add_landmark_options(script, required=False, note=" (for scripts whose filter uses landmarks)")
    add_missing_option(script)
    script.add_argument("-o", "--output", required=True, type=pathlib.Path,
                        help="the current mesh after the script; .ply keeps quality and the attributes")
    script.add_argument("--report", type=pathlib.Path, help="write every filter's output as JSON")
    script.add_argument("--overwrite", action="store_true", help="allow -o to name the input mesh (replaced at the end)")
    script.add_argument("--accept-replacements", action="store_true",
                        help="run the recorded replacement of a filter MeshLab removed (e.g. the old Poisson "
                             "reconstruction as Screened Poisson), each printed and kept in the report")
    script.set_defaults(handler=run)


def run(args) -> int:
    """The command: every output checked, the landmarks stored, the script applied, the mesh and report written."""
    check_outputs(args, {"output mesh": args.output, "report": args.report, "pair table": args.save_pair_table},
                   [args.input, args.script, args.landmarks])
    ours = [symblend_options(node, args.script) for node in read_filter_script(args.script) if node.is_symblend]
    needs_landmarks = [options for options in ours if options["pairs"] != "auto"]
    if needs_landmarks and not args.landmarks:
        raise SymblendError(f"{args.script} runs the filter with pairs='{needs_landmarks[0]['pairs']}'; give the "
                            "landmark file with -l LANDMARKS (or use a script whose pairs are 'auto').")
    ms = load_mesh(args.input)
    landmarks = None
    if args.landmarks:
        options = ours[0] if ours else DEFAULTS
        landmarks = write_landmarks(ms, args, options)
        if landmarks["curves"] and not options["width_spacing"]:
            warnings.warn(f"{args.script} has width_spacing 0, so its widths are multiples of the semilandmark "
                          f"spacing; set width_spacing to {landmarks['placed_point_spacing']:.4g} (the spacing of "
                          "the placed points) in the script to keep them as without curves.", SymblendWarning)
    steps = apply_filter_script(ms, args.script, progress_display(), args.accept_replacements)
    for number, step in enumerate(steps, start=1):
        if "translated" in step:
            print(f"{args.script}, filter {number}: {step['translated']}", file=sys.stderr)
    save_with_report(ms, args.output, args.report, {"script": str(args.script), "landmarks": landmarks,
                                                    "accept_replacements": args.accept_replacements, "steps": steps})
    print(f"{args.output}: {len(steps)} filters of {args.script} applied")
    return 0
