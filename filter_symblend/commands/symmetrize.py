"""``symblend symmetrize INPUT (-l LANDMARKS | --pairs auto) -o OUTPUT``: one mesh, from a landmark file
or from automatic pairs, through the MeshSet filter; the output mesh and the JSON report written."""

from __future__ import annotations

import dataclasses
import functools
import sys

import pymeshlab

from ..core.placement import PLACEMENT_DRAWS
from ..core.report import UncertaintySummary
from ..errors import SymblendError
from ..meshlab.meshset_filter import FilterRun, run_filter
from ..parameters import PARAMETERS
from .shared.console import progress_display
from .shared.landmark_input import read_landmarks
from .shared.mesh_io import check_outputs, load_mesh, save_with_report
from .shared.options import add_symmetrize_arguments


POINTS_ONLY = (".xyz",)  # mesh formats pymeshlab writes without faces


def register(commands) -> None:
    """Add the command to ``commands`` (argparse subparsers)."""
    parser = commands.add_parser("symmetrize", help="symmetrize a mesh from landmark pairs or automatic pairs")
    add_symmetrize_arguments(parser)
    parser.set_defaults(handler=run)


@dataclasses.dataclass(frozen=True)
class Symmetrized:
    """One mesh symmetrized by the command: the filter's ``run`` (its typed report), the landmark file's
    ``landmarks`` as read (commands/landmark_input; None with automatic pairs alone) and the MeshSet ``ms``
    holding the output as its current mesh."""

    run: FilterRun
    landmarks: dict | None
    ms: pymeshlab.MeshSet

    @functools.cached_property
    def document(self) -> dict:
        """The JSON report written by ``--report``: the filter's, with the landmark names under ``landmarks``
        (built once: the file and a batch row's summary read the same)."""
        return {**self.run.to_dict(), "landmarks": self.landmarks}


def symmetrize_files(args, progress=None) -> Symmetrized:
    """``symblend symmetrize`` without its printout, for one parsed command line ``args``: every check,
    then the filter, the output mesh and the report written."""
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
    pairs, landmarks = (None, None) if automatic else read_landmarks(ms, args)
    if landmarks and landmarks["curves"] and not params["width_spacing"]:
        params["width_spacing"] = landmarks["placed_point_spacing"]  # semilandmarks leave the widths as they were
    done = Symmetrized(run_filter(ms, params, progress, landmarks=pairs), landmarks, ms)
    save_with_report(ms, args.output, args.report, done.document)
    return done


def run(args) -> int:
    """The command: :func:`symmetrize_files`, then one line of figures on stdout and the warnings on stderr."""
    done = symmetrize_files(args, progress_display())
    report = done.run.report
    pairs = f"{report.pair_count} landmark pairs"
    if report.auto_pairs is not None:
        automatic = report.auto_pairs
        pairs += (f" + {automatic.pair_count} automatic pairs ({len(automatic.rounds)} rounds, "
                  f"stopped: {automatic.stopped}; confident twins on "
                  f"{automatic.mirror_map.confident_share:.0%} of the surface)")
    landmark_line = ""
    if report.landmark_asymmetry_before is not None:
        landmark_line = (f"landmark asymmetry RMS {report.landmark_asymmetry_before.rms_relative:.2%} -> "
                         f"{report.landmark_asymmetry_after.rms_relative:.1e} of the diagonal; ")
    checks = ""
    if report.checks is not None:
        before, after = report.checks.before, report.checks.after
        checks = ("mirror asymmetry of the diagonal, before -> after: " + ", ".join(
            f"{label} {before[key + '_relative']:.3%} -> {after[key + '_relative']:.3%}"
            for label, key in (("median", "p50"), ("p90", "p90"), ("RMS", "rms"))))
        if report.checks.hausdorff is not None:
            checks += f"; two-way Hausdorff input<->output {report.checks.hausdorff['max']:.4g}"
    print(f"{args.output}: {pairs}, mode {report.mode}; {landmark_line}{checks}".rstrip("; "))
    if report.uncertainty is not None:
        print(uncertainty_line(report.uncertainty, done.landmarks))
    for message in report.checks.warnings if report.checks is not None else ():
        print(f"warning: {message}", file=sys.stderr)
    return 0


def landmark_name(unit: str, landmarks: dict | None) -> str:
    """The file's names for a pair id or ``midline k`` of the filter's report (the id when not from a file)."""
    if not landmarks:
        return f"pair {unit}" if unit.isdigit() else unit
    if unit.isdigit():
        return "/".join(landmarks["pairs"][int(unit) - 1])
    return landmarks["midline"][int(unit.split()[-1]) - 1]


def uncertainty_line(uncertainty: UncertaintySummary, landmarks: dict | None) -> str:
    """One line of the report's ``uncertainty``: the most influential pair, and the probably misplaced one, by
    their landmark names."""
    top, misplaced = uncertainty.most_influential_pair, uncertainty.probably_misplaced
    turns = ("in turn" if uncertainty.groups in (None, uncertainty.left_out)
             else f"in {uncertainty.groups} random groups")
    spread = (f"jackknife, {uncertainty.left_out} landmarks left out {turns}" if uncertainty.method == "jackknife" else
              f"placement error of {uncertainty.landmark_precision:.4g} RMS, {PLACEMENT_DRAWS} random placements")
    line = (f"uncertainty ({spread}): median "
            f"{uncertainty.median_relative:.3%}, p90 {uncertainty.p90_relative:.3%}, max "
            f"{uncertainty.max_relative:.3%} of the diagonal; most influential: {landmark_name(top, landmarks)} "
            f"(the result moves up to {uncertainty.influence_relative[top]:.3%} without it)")
    if misplaced is not None:
        line += (f"; probably misplaced: {landmark_name(misplaced, landmarks)} (the others' restoration leaves it "
                 f"{uncertainty.mirror_error_relative[misplaced]:.3%} of the diagonal from mirroring)")
    return line
