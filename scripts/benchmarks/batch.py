"""--batch: `symblend batch` over a study of 16 specimens, with 1 and 2 local workers and on a local Dask cluster."""

from __future__ import annotations

import os
import pathlib
import sys
import tempfile
import time

import pymeshlab

from filter_symblend.testing import synthetic

from .common import MESHES, child, subdivided_cows

BATCH_SPECIMENS = 16
BATCH_PAIRS = 100


def _batch_study(folder: pathlib.Path) -> pathlib.Path:
    """16 copies of the cow midpoint-subdivided twice (46k vertices), each bent by its own angle and posed, with 100
    landmark pairs: the manifest."""
    from filter_symblend.landmarks.formats import Landmark, LandmarkSet, write_landmarks

    *_, (points, offset, partner) = subdivided_cows(2)
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(MESHES["cow"]))
    ms.meshing_surface_subdivision_midpoint(iterations=2, threshold=pymeshlab.PercentageValue(0))
    faces = ms.current_mesh().face_matrix()
    left, right = synthetic.spread_pairs(points, offset, partner, BATCH_PAIRS)
    rows = []
    for index in range(BATCH_SPECIMENS):
        bent = synthetic.random_rigid(synthetic.bend(points, 0.1 + 0.05 * index), seed=index)
        specimen = pymeshlab.MeshSet()
        specimen.add_mesh(pymeshlab.Mesh(vertex_matrix=bent, face_matrix=faces))
        specimen.save_current_mesh(str(folder / f"cow_{index:02d}.ply"))
        write_landmarks(folder / f"cow_{index:02d}.pp", LandmarkSet([
            Landmark(f"{side}_{k}", tuple(bent[v])) for k, (a, b) in enumerate(zip(left, right))
            for side, v in (("L", a), ("R", b))]))
        rows.append(f"cow_{index:02d}.ply,cow_{index:02d}.pp")
    manifest = folder / "manifest.csv"
    manifest.write_text("mesh,landmarks\n" + "\n".join(rows) + "\n")
    return manifest


# `symblend batch` in a process of its own; its peak RSS and its workers' largest, MB, on the last line.
BATCH_PROCESS = ("import resource, sys; from filter_symblend.commands.main import main; code = main(sys.argv[1:]); "
                 "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, "
                 "resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024)")


def batch_main() -> None:
    """`symblend batch` over 16 specimens: wall time with 1 and 2 local workers and on a local Dask cluster."""
    print(f"\n`symblend batch`, {BATCH_SPECIMENS} bent cows of {len(list(subdivided_cows(2))[-1][0]):,} vertices, "
          f"{BATCH_PAIRS} landmark pairs each ({time.strftime('%Y-%m-%d')}, {os.cpu_count()} cores)")
    print("| run | workers | wall s | s per specimen | speed-up | peak RSS MB: main / largest worker |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        manifest = _batch_study(pathlib.Path(folder))
        first = None
        for name, workers in (("local pool", 1), ("local pool", 2)):
            out, seconds = child([sys.executable, "-c", BATCH_PROCESS, "batch", str(manifest), "-o",
                                   str(pathlib.Path(folder) / f"out_{workers}"), "--workers", str(workers)])
            main_rss, worker_rss = out.strip().splitlines()[-1].split()
            first = first or seconds
            print(f"| {name} | {workers} | {seconds:.1f} | {seconds / BATCH_SPECIMENS:.2f} | {first / seconds:.2f}x | "
                  f"{float(main_rss):.0f} / {float(worker_rss):.0f} |", flush=True)
        from dask.distributed import LocalCluster

        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                          dashboard_address=None) as cluster:
            out, seconds = child([sys.executable, "-c", BATCH_PROCESS, "batch", str(manifest), "-o",
                                   str(pathlib.Path(folder) / "out_dask"), "--scheduler", cluster.scheduler_address])
        print(f"| local Dask cluster | 2 | {seconds:.1f} | {seconds / BATCH_SPECIMENS:.2f} | {first / seconds:.2f}x | "
              f"{float(out.strip().splitlines()[-1].split()[0]):.0f} / - (Dask's workers are not its children) |",
              flush=True)
