"""Accuracy and speed against ground truth, with the mirror-averaging baseline beside it.

Exactly symmetric meshes (pymeshlab's cow; spot from ../shared/data when present)
are deformed by known maps; pairs are farthest-point mirror pairs. For each
scenario x pair count, every mode and the baseline report:
  shape: RMS distance to the undeformed mesh after similarity alignment, % of
         the diagonal (for "articulated", on the two legs only: the symmetric
         pose of a limb is a choice, its shape is not);
  sym:   RMS over ALL ground-truth vertex pairs of |left - mirror(right)|,
         % of the diagonal.
Seconds are the filter's own stage timings (median of --repeat runs).

    python scripts/benchmark.py [--pairs 100 300 1000] [--repeat 3] [--meshes cow spot]
    python scripts/benchmark.py --scale      # speed and memory at scale, and the paper's Table 1
    python scripts/benchmark.py --auto       # automatic pairs against 100 landmark pairs, landmarks+auto with
                                             # 10-100 landmarks, automatic pairs on the Igea scan
    python scripts/benchmark.py --corpus     # pairs='auto' on every mesh of ../shared/data and pymeshlab's
                                             # samples, as given and deformed; synthetic meshes as they come
    python scripts/benchmark.py --filter     # what the user runs: the MeshSet filter against its core, and
                                             # `symblend report`, each in its own process (time, peak RSS)
    python scripts/benchmark.py --mirror-maps [--quick | --half H | --all-shapes] [--bcicp PATH] [--no-pyfm]
                                             # the automatic pairs' mirror map against the ground-truth
                                             # self-symmetry of FAUST and TOSCA (BCICP dataset), pyFM beside it
    python scripts/benchmark.py --batch      # `symblend batch` on 16 specimens of about 30k vertices: 1 and 2
                                             # local workers, and a local Dask cluster
    python scripts/benchmark.py --uncertainty [--quick]  # the jackknife and the placement band: their cost through
                                             # the MeshSet filter, their calibration against known landmark
                                             # noise, a misplaced landmark
    python scripts/benchmark.py --icp        # the mirror plane's reflection ICP, plain and Anderson-accelerated
    python scripts/benchmark_dense.py        # dense pairs: the stages, the warp against the dense spline

Each section is a module of scripts/benchmarks/ (accuracy, scale, automatic, corpus, whole_filter, batch,
mirror_maps, uncertainty, mirror_planes) on the
package's own helpers; this script only parses the options and runs one.
"""

from __future__ import annotations

import argparse
import warnings

from filter_symblend import SymblendWarning

from benchmarks import (accuracy, automatic, batch, corpus, mirror_maps, mirror_planes, scale,  # scripts/ is on sys.path
                        uncertainty, whole_filter)
from benchmarks.common import MESHES


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--pairs", type=int, nargs="+", default=[100, 300, 1000])
    parser.add_argument("--repeat", type=int, default=3, help="runs per cell for the timings")
    parser.add_argument("--meshes", nargs="+", default=list(MESHES), choices=list(MESHES))
    parser.add_argument("--scale", action="store_true", help="speed and memory at scale, and Table 1")
    parser.add_argument("--auto", action="store_true", help="automatic pairs against 100 landmark pairs")
    parser.add_argument("--corpus", action="store_true", help="automatic pairs over every corpus mesh")
    parser.add_argument("--filter", action="store_true", help="the MeshSet filter against its core; symblend report")
    parser.add_argument("--batch", action="store_true", help="symblend batch: 1 and 2 workers, a local Dask cluster")
    parser.add_argument("--icp", action="store_true", help="the mirror plane's reflection ICP, plain and accelerated")
    parser.add_argument("--uncertainty", action="store_true", help="the jackknife and the placement band: cost, calibration, detection")
    parser.add_argument("--mirror-maps", action="store_true",
                        help="the mirror map against the BCICP dataset's ground-truth self-symmetry")
    parser.add_argument("--quick", action="store_true",
                        help="--mirror-maps: six shapes (about 2 minutes); --uncertainty: 6 sets a cell, not 12 (4 draws, not 10)")
    parser.add_argument("--all-shapes", action="store_true", help="--mirror-maps: every FAUST and TOSCA shape")
    parser.add_argument("--half", choices=["both", "chosen", "checked"], default="both",
                        help="--mirror-maps: the shapes the choices were made on, those kept to check them, or both")
    parser.add_argument("--shapes", nargs="+", help="--mirror-maps: these shapes only (e.g. tr_reg_088 cat4)")
    parser.add_argument("--bcicp", help="--mirror-maps: the dataset (a git snapshot or an unpacked copy)")
    parser.add_argument("--no-pyfm", action="store_true", help="--mirror-maps: leave out the pyFM baseline")
    parser.add_argument("--mode", default="articulated", help="--mirror-maps: the filter's mode")
    parser.add_argument("--filter-row", nargs=3, metavar=("MESH", "PAIRS", "CHECKS"), help=argparse.SUPPRESS)
    parser.add_argument("--levels", type=int, default=4, help="--scale: subdivisions of the cow (4: 743k vertices)")
    parser.add_argument("--scale-pairs", type=int, nargs="+", default=[100, 1000, 10000, 100000])
    parser.add_argument("--warp-pairs", type=int, nargs="+", default=[2000, 20000],
                        help="--scale: pair counts of the mesh-size rows")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore", SymblendWarning)
    if args.scale:
        scale.scale_main(args)
        return
    if args.corpus:
        corpus.corpus_main()
        return
    if args.mirror_maps:
        mirror_maps.mirror_maps_main(args)
        return
    if args.filter_row:
        whole_filter.filter_row(args.filter_row[0], int(args.filter_row[1]), args.filter_row[2])
        return
    if args.filter:
        whole_filter.filter_main()
        return
    if args.batch:
        batch.batch_main()
        return
    if args.icp:
        mirror_planes.icp_main()
        return
    if args.uncertainty:
        uncertainty.uncertainty_main(args)
        return
    if args.auto:
        automatic.auto_main(args)
        automatic.auto_landmark_counts(args)
        automatic.auto_scans()
        return
    accuracy.accuracy_main(args)


if __name__ == "__main__":
    main()
