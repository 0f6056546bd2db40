"""--filter: the MeshSet filter as a user calls it against its core, and `symblend report`, every row in a fresh
process so that its peak RSS is its own."""

from __future__ import annotations

import json
import os
import pathlib
import resource
import sys
import tempfile
import time

import numpy as np
import pymeshlab

from filter_symblend.testing import synthetic

from .common import IGEA, SCAN_OPTIONS, child, igea_meshes, scan_pairs

ENTRY = pathlib.Path(__file__).resolve().parents[1] / "benchmark.py"  # the script a row's child process runs
# --filter rows: (name, Igea faces after decimation or None for subdivided twice, landmark pairs, checks)
# 'none' first: with checks on, the input's check runs beside the warp and slows the core it shares the CPU
# with, so each row is set against the core of the mesh's 'none' row.
FILTER_ROWS = (("igea 32k", 64_000, 1000, "none"), ("igea 32k", 64_000, 1000, "mirror"),
               ("igea 32k", 64_000, 1000, "full"), ("igea 1M", None, 2000, "none"), ("igea 1M", None, 2000, "mirror"))
REPORT_ROWS = (("igea 61k", 122_000), ("igea 1M", None))
AUTO_ROWS = (("igea", 0), ("igea 1M", None))  # --filter's automatic-pairs rows: Igea as scanned (0), subdivided twice


def _filter_mesh(path: pathlib.Path, faces: int | None) -> None:
    """Igea decimated to ``faces`` faces (None: subdivided twice, 1.02 x 10^6 vertices): a PLY at ``path``."""
    if faces is None:
        *_, (_, points, triangles) = igea_meshes()
    else:
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(IGEA))
        ms.meshing_remove_unreferenced_vertices()
        ms.meshing_decimation_quadric_edge_collapse(targetfacenum=faces)
        points, triangles = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=points, face_matrix=triangles))
    ms.save_current_mesh(str(path))


def filter_row(mesh: str, pairs: int, checks: str) -> None:
    """One --filter row in this process, on ``mesh`` bent and compressed (the paper's Figure 1 map) with
    ``pairs`` approximate mirror pairs found before the deformation: print JSON {vertices, pairs, core and
    total seconds, peak RSS MB}; the deformed input and the output are saved beside ``mesh`` (_in, _out)."""
    import filter_symblend  # noqa: F401  (binds the filter)

    loaded = pymeshlab.MeshSet()
    loaded.load_new_mesh(mesh)
    points, faces = loaded.current_mesh().vertex_matrix(), loaded.current_mesh().face_matrix()
    [(_, left, right)] = scan_pairs(points, [pairs])
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=synthetic.figure_1_deformation(points), face_matrix=faces))
    ms.save_current_mesh(mesh.replace(".ply", "_in.ply"))
    labels = np.zeros(len(points))
    labels[left], labels[right] = np.arange(1, len(left) + 1), -np.arange(1, len(left) + 1)
    ms.current_mesh().add_vertex_custom_scalar_attribute(labels, "symblend_pair")
    options = {**SCAN_OPTIONS, **({} if checks == "default" else {"checks": checks})}
    start = time.perf_counter()
    report = ms.generate_symmetrized_mesh(**options)
    total = time.perf_counter() - start
    ms.save_current_mesh(mesh.replace(".ply", "_out.ply"))
    print(json.dumps({"vertices": len(points), "pairs": len(left), "core": report["seconds"]["total"],
                      "checks": report["seconds"]["checks"], "total": total,
                      "rss": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))


# A `symblend` command as the console script runs it, then the process's own peak RSS (MB) on the last line.
SYMBLEND_PROCESS = ("import resource, sys; from filter_symblend.commands.main import main; code = main(sys.argv[1:]); "
                    "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024); sys.exit(code)")


def filter_main() -> None:
    """The MeshSet filter as a user calls it, against its core (report seconds.total), and `symblend report`
    on its output; every row in a fresh process, so its peak RSS is its own."""
    if not IGEA.exists():
        print(f"--filter: skipped, {IGEA} is absent")
        return
    print(f"\nThe whole filter against its core ({time.strftime('%Y-%m-%d')}, {os.cpu_count()} cores): Igea, "
          "Figure 1 map, approximate mirror pairs; standard mode, phi width 8; peak RSS of the process")
    print("Each check's own seconds, in its thread beside the core: the input's (its planes, then its figures), the "
          "output's, the two-way Hausdorff distance.")
    print("| mesh | vertices | pairs | checks | core s | input's check s | output's s | Hausdorff s | filter s "
          "| filter / core of 'none' | peak RSS MB |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        made, core = {}, {}
        for name, faces, pairs, checks in FILTER_ROWS:
            path = made.setdefault(name, str(pathlib.Path(folder) / f"{name.replace(' ', '_')}.ply"))
            if not pathlib.Path(path).exists():
                _filter_mesh(pathlib.Path(path), faces)
            out, _ = child([sys.executable, str(ENTRY), "--filter-row", path, str(pairs), checks])
            row = json.loads(out.strip().splitlines()[-1])
            core.setdefault(name, row["core"])
            measured = row["checks"]
            own = [measured.get("input_planes", 0.0) + measured.get("mirror_asymmetry_before", 0.0),
                   measured.get("mirror_asymmetry_after", 0.0), measured.get("hausdorff_input_output", 0.0)]
            cells = " | ".join(f"{value:.2f}" if value else "-" for value in own)
            print(f"| {name} | {row['vertices']:,} | {row['pairs']:,} | {checks} | {row['core']:.2f} | {cells} | "
                  f"{row['total']:.2f} | {row['total'] / core[name]:.2f} | {row['rss']:.0f} |", flush=True)
        print("\n`symblend report BEFORE AFTER` (the process as a whole, start-up included)")
        print("| mesh | vertices | s | peak RSS MB |")
        print("|---|---|---|---|")
        for name, faces in REPORT_ROWS:
            path = made.get(name) or str(pathlib.Path(folder) / f"{name.replace(' ', '_')}.ply")
            if not pathlib.Path(path).exists():
                _filter_mesh(pathlib.Path(path), faces)
            before, after = path.replace(".ply", "_in.ply"), path.replace(".ply", "_out.ply")
            if not pathlib.Path(after).exists():
                child([sys.executable, str(ENTRY), "--filter-row", path, "2000", "none"])
            out, seconds = child([sys.executable, "-c", SYMBLEND_PROCESS, "report", before, after])
            rss = float(out.strip().splitlines()[-1])
            vertices = pymeshlab.MeshSet()
            vertices.load_new_mesh(path)
            print(f"| {name} | {vertices.current_mesh().vertex_number():,} | {seconds:.1f} | {rss:.0f} |", flush=True)
        auto_rows(made, folder)


def auto_rows(made: dict, folder: str) -> None:
    """`symblend symmetrize MESH --pairs auto` on Igea as scanned and subdivided twice, each in a fresh process
    (loading and writing included): seconds and peak RSS (issue 46's targets: 134k vertices <= 20 s, 10^6 <= 120 s
    and 4 GB). ``made``: meshes already written in ``folder`` by name."""
    print("\n`symblend symmetrize MESH --pairs auto` (the process as a whole, start-up, reading and writing included)")
    print("| mesh | vertices | s | peak RSS MB | the map |")
    print("|---|---|---|---|---|")
    for name, faces in AUTO_ROWS:
        written = str(pathlib.Path(folder) / f"{name.replace(' ', '_')}.ply")
        path = str(IGEA) if faces == 0 else made.get(name) or written
        if not pathlib.Path(path).exists():
            _filter_mesh(pathlib.Path(path), faces)
        output, report = written.replace(".ply", "_auto.ply"), written.replace(".ply", "_auto.json")
        out, seconds = child([sys.executable, "-c", SYMBLEND_PROCESS, "symmetrize", path, "--pairs", "auto",
                              "-o", output, "--report", report])
        rss = float(out.strip().splitlines()[-1])
        found = json.loads(pathlib.Path(report).read_text())
        vertices = pymeshlab.MeshSet()
        vertices.load_new_mesh(path)
        print(f"| {name} | {vertices.current_mesh().vertex_number():,} | {seconds:.1f} | {rss:.0f} | "
              f"{found['auto_pairs']['mirror_map']['map']} |", flush=True)
