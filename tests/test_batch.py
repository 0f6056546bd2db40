"""symblend batch: a study of deformed ground-truth meshes, locally and on a Dask cluster, with a bad row."""

import csv
import os
import pathlib

import numpy as np
import pymeshlab
import pytest

from filter_symblend import SymblendError
from filter_symblend.commands.batch import read_manifest, run
from filter_symblend.commands.main import main
from filter_symblend.core.landmark_asymmetry import fit_mirror_plane
from filter_symblend.landmarks.formats import Landmark, LandmarkSet, read_landmarks, write_landmarks
from filter_symblend.testing import synthetic
from conftest import SAMPLE_MESHES

BENDS = {"cow_a": 0.2, "cow_b": 0.4, "cow_c": 0.6}


@pytest.fixture(scope="module")
def study(tmp_path_factory, cow):
    """Three bent cows with 30 landmark pairs each (one row in the affine mode), and a row whose mesh is
    missing: (manifest, folder)."""
    folder = tmp_path_factory.mktemp("study")
    left, right = cow.landmarks(30)
    for seed, (name, angle) in enumerate(BENDS.items()):
        bent = synthetic.random_rigid(synthetic.bend(cow.points, angle), seed=seed)
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(vertex_matrix=bent, face_matrix=cow.faces))
        ms.save_current_mesh(str(folder / f"{name}.ply"))
        write_landmarks(folder / f"{name}.pp", LandmarkSet([
            Landmark(f"{side}_{k}", tuple(bent[v])) for k, (a, b) in enumerate(zip(left, right))
            for side, v in (("L", a), ("R", b))]))
    (folder / "manifest.csv").write_text("mesh,landmarks,mode\n" + "cow_a.ply,cow_a.pp,\n" + "cow_b.ply,cow_b.pp,affine\n"
                                         + "lost.ply,cow_a.pp,\n" + "cow_c.ply,cow_c.pp,\n")
    return folder / "manifest.csv", folder


def _points(path) -> np.ndarray:
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    return ms.current_mesh().vertex_matrix()


def _summary(outdir: pathlib.Path) -> list[dict]:
    with open(outdir / "summary.csv", newline="") as handle:
        return list(csv.DictReader(handle))


@pytest.fixture(scope="module")
def local_run(study, tmp_path_factory):
    manifest, folder = study
    outdir = tmp_path_factory.mktemp("out") / "symmetrized"  # created by the run
    code = main(["batch", str(manifest), "-o", str(outdir), "--workers", "2", "--phi-width", "6"])
    return code, outdir


def test_the_local_pool_gives_what_symmetrize_gives_one_by_one(study, local_run, tmp_path, capsys):
    manifest, folder = study
    code, outdir = local_run
    assert code == 1  # one row failed
    rows = _summary(outdir)
    assert [pathlib.Path(r["mesh"]).name for r in rows] == ["cow_a.ply", "cow_b.ply", "lost.ply", "cow_c.ply"]
    assert [r["status"] for r in rows] == ["ok", "ok", "failed", "ok"]
    assert "lost.ply: no such mesh file" in rows[2]["error"]
    assert rows[2]["output"] == "" and all(pathlib.Path(r["output"]).exists() for r in rows if r["status"] == "ok")
    for name, mode in (("cow_a", "standard"), ("cow_b", "affine"), ("cow_c", "standard")):
        alone = tmp_path / f"{name}.ply"
        assert main(["symmetrize", str(folder / f"{name}.ply"), "-l", str(folder / f"{name}.pp"), "-o", str(alone),
                     "--mode", mode, "--phi-width", "6"]) == 0
        np.testing.assert_allclose(_points(outdir / f"{name}.ply"), _points(alone), rtol=0, atol=1e-9)
        assert (outdir / f"{name}.json").exists()
        row = rows[["cow_a", "cow_b", "lost", "cow_c"].index(name)]
        assert float(row["landmark_asymmetry_after"]) < 1e-9 < float(row["landmark_asymmetry_before"])
    # The study's symmetrized landmarks, one TPS specimen per mesh: exactly mirror-symmetric pairs.
    for name in BENDS:
        landmarks = read_landmarks(outdir / "landmarks.tps", name)
        xyz = np.array([lm.position for lm in landmarks.landmarks])
        assert len(xyz) == 60
        assert fit_mirror_plane(xyz[:30], xyz[30:]).deviations.max() < 1e-9


def test_a_rerun_skips_the_rows_already_done(study, local_run, capsys):
    manifest, _ = study
    _, outdir = local_run
    written = {name: os.stat(outdir / f"{name}.ply").st_mtime_ns for name in BENDS}
    assert main(["batch", str(manifest), "-o", str(outdir), "--workers", "1", "--phi-width", "6"]) == 1
    assert "3 of 4 specimens symmetrized, 3 of them done before; 1 failed" in capsys.readouterr().out
    assert [r["status"] for r in _summary(outdir)] == ["done before", "done before", "failed", "done before"]
    assert {name: os.stat(outdir / f"{name}.ply").st_mtime_ns for name in BENDS} == written
    assert len(read_landmarks(outdir / "landmarks.tps", "cow_c").landmarks) == 60


def test_a_dask_cluster_runs_the_same_rows(study, local_run, tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    manifest, _ = study
    _, local = local_run
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        summaries = run(manifest, tmp_path / "dask", ["--phi-width", "6"], scheduler=cluster.scheduler_address)
    assert [s["status"] for s in summaries] == ["ok", "ok", "failed", "ok"]
    for name in BENDS:
        np.testing.assert_allclose(_points(tmp_path / "dask" / f"{name}.ply"), _points(local / f"{name}.ply"),
                                   rtol=0, atol=1e-9)


@pytest.mark.parametrize("text, message", [
    ("landmarks\na.pp\n", r"needs a header row with a `mesh` column .*got landmarks"),
    ("mesh,colour\na.ply,red\n", r"column 'colour' is not an option of symblend symmetrize .*valid columns: mesh, "),
    ("mesh,output\na.ply,b.ply\n", r"column 'output' is not an option"),
    ("mesh,midline\na.ply,maybe\n", r"line 2: 'maybe' for the flag `midline`; write true or false"),
    ("mesh\na.ply\nsub/a.ply\n", r"line 3: a.ply has the same name as the mesh of line 2"),
    ("mesh,landmarks\n\n,a.pp\n", r"line 3: the mesh cell is empty"),
])
def test_manifest_errors(tmp_path, text, message):
    (tmp_path / "m.csv").write_text(text)
    with pytest.raises(SymblendError, match=message):
        read_manifest(tmp_path / "m.csv", tmp_path)


def test_row_options_override_the_defaults(tmp_path):
    (tmp_path / "m.csv").write_text("mesh,landmarks,mode,midline,pair-table\nskull.ply,skull.tps,affine,true,p.csv\n")
    [row] = read_manifest(tmp_path / "m.csv", tmp_path / "out", ["--mode", "standard", "--phi-width", "6"])
    words = list(row.arguments)
    assert words[0] == str(tmp_path / "skull.ply")
    assert words[words.index("--landmarks") + 1] == str(tmp_path / "skull.tps")  # relative to the manifest
    assert words[words.index("--pair-table") + 1] == str(tmp_path / "p.csv")
    assert words.index("--mode", 2) > words.index("standard")  # the row's mode comes last and wins
    assert "--midline" in words and row.output == tmp_path / "out" / "skull.ply"


def test_batch_command_errors(tmp_path, capsys, monkeypatch):
    (tmp_path / "m.csv").write_text("mesh\na.ply\n")
    assert main(["batch", str(tmp_path / "m.csv"), "-o", str(tmp_path / "out"), "--workers", "0"]) == 1
    assert "--workers 0: give 1 or more processes" in capsys.readouterr().err
    assert main(["batch", str(tmp_path / "m.csv"), "-o", str(tmp_path / "no" / "out")]) == 1
    assert "give a folder for the outputs (its parent folder must exist)" in capsys.readouterr().err
    monkeypatch.setitem(__import__("sys").modules, "dask.distributed", None)
    assert main(["batch", str(tmp_path / "m.csv"), "-o", str(tmp_path / "out"), "--scheduler", "tcp://127.0.0.1:1"]) == 1
    assert "dask.distributed is not installed; pip install 'filter-symblend[cluster]'" in capsys.readouterr().err


def test_an_unexpected_failure_of_one_row_is_reported_not_raised(study, monkeypatch):
    import filter_symblend.commands.batch as batch
    manifest, folder = study
    [row, *_] = read_manifest(manifest, folder / "unexpected")

    def broken(args, progress=None):
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(batch, "symmetrize_files", broken)
    summary = batch.run_row(row)
    assert summary["status"] == "failed" and summary["error"] == "unexpected RuntimeError: disk on fire (please report it)"


def test_more_batch_errors(tmp_path, study, capsys, monkeypatch):
    import filter_symblend.commands.batch as batch
    pytest.importorskip("dask.distributed")
    manifest, folder = study
    with pytest.raises(SymblendError, match=r"nothere.csv: cannot be read \(No such file or directory\)"):
        read_manifest(tmp_path / "nothere.csv", tmp_path)
    monkeypatch.setattr(batch, "SCHEDULER_TIMEOUT", 2)
    with pytest.raises(SymblendError, match=r"--scheduler tcp://127.0.0.1:9: no Dask scheduler answers there"):
        run(manifest, tmp_path / "out", scheduler="tcp://127.0.0.1:9")
    (tmp_path / "m.csv").write_text(f"mesh,landmarks,mode\n{folder / 'cow_a.ply'},{folder / 'cow_a.pp'},stretchy\n")
    [row] = read_manifest(tmp_path / "m.csv", tmp_path / "out")
    summary = batch.run_row(row)  # a bad option value fails its row, with argparse's own words
    assert summary["status"] == "failed"
    assert summary["error"] == "argument --mode: invalid choice: 'stretchy' (choose from 'standard', 'affine', 'articulated')"


def _lock(outdir: pathlib.Path, pid: int) -> pathlib.Path:
    import json
    import socket
    from filter_symblend.commands.shared.folder_lock import LOCK_NAME
    lock = outdir / LOCK_NAME
    lock.write_text(json.dumps({"pid": pid, "host": socket.gethostname(), "since": "2026-12-05 10:00:00"}))
    return lock


def test_a_folder_another_batch_is_writing_is_refused_naming_that_run(study, tmp_path, capsys):
    """Two batches on one folder: the second stops at once, saying which run holds it, and writes nothing;
    with --wait it waits for the other to end, then runs."""
    import subprocess
    import sys
    import time
    manifest, _ = study
    outdir = tmp_path / "shared"
    outdir.mkdir()
    import threading
    holder = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(3)"])
    threading.Thread(target=holder.wait, daemon=True).start()  # reaped when it ends, as its own parent would
    try:
        lock = _lock(outdir, holder.pid)
        assert main(["batch", str(manifest), "-o", str(outdir)]) == 1
        assert capsys.readouterr().err == (
            f"symblend: error: {outdir}: another symblend batch (process {holder.pid} on {os.uname().nodename}, "
            f"since 2026-12-05 10:00:00) is writing this folder; wait for it (--wait), or give another folder. "
            f"If no such run exists, delete {lock}.\n")
        assert sorted(p.name for p in outdir.iterdir()) == [lock.name]
        start = time.perf_counter()
        assert main(["batch", str(manifest), "-o", str(outdir), "--wait", "--workers", "1"]) == 1  # a row fails
        assert time.perf_counter() - start > 1.0 and holder.poll() is not None  # it waited for the holder
    finally:
        holder.kill()
    assert len(_summary(outdir)) == 4 and not lock.exists()


def test_a_lock_left_by_a_killed_batch_is_taken_over(study, tmp_path):
    import subprocess
    import sys
    manifest, _ = study
    outdir = tmp_path / "after_a_crash"
    outdir.mkdir()
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    lock = _lock(outdir, int(gone.stdout))
    assert main(["batch", str(manifest), "-o", str(outdir), "--workers", "1"]) == 1  # the lost.ply row fails
    assert [row["status"] for row in _summary(outdir)] == ["ok", "ok", "failed", "ok"]
    assert not lock.exists()


def test_the_summary_gives_the_confident_share_of_automatic_pairs(study, tmp_path):
    """A row with automatic pairs says how much of its surface has a confident twin (its report's figure); a row
    with landmarks alone leaves the column empty."""
    import json
    manifest, folder = study
    mixed = folder / "mixed.csv"
    mixed.write_text("mesh,landmarks,pairs\ncow_a.ply,,auto\ncow_b.ply,cow_b.pp,landmarks\n")
    outdir = tmp_path / "mixed"
    assert main(["batch", str(mixed), "-o", str(outdir), "--workers", "1"]) == 0
    auto, landmarks = _summary(outdir)
    report = json.loads((outdir / "cow_a.json").read_text())
    assert float(auto["confident_share"]) == pytest.approx(report["auto_pairs"]["mirror_map"]["confident_share"],
                                                           rel=1e-3)
    assert 0.9 < float(auto["confident_share"]) <= 1.0 and landmarks["confident_share"] == ""


WORKER_IN_A_FINALIZER = """
import sys, time
from filter_symblend.atomic import all_or_none
from filter_symblend.commands.batch import _start_worker

class Slow:
    def __del__(self):  # SIGTERM arrives here: an exception raised by the handler would be ignored
        print("ready", flush=True)
        time.sleep(5)

_start_worker()
with all_or_none([sys.argv[1], sys.argv[2]]) as (mesh, report):
    mesh.write_text("partial mesh")
    Slow()
    report.write_text("partial report")
"""


def test_a_worker_stopped_inside_a_finalizer_exits_at_once_and_leaves_no_partial_file(tmp_path):
    """SIGTERM reaches a batch worker wherever Python is, a finalizer included (where an exception raised by
    the handler is ignored and the row went on): the worker exits 143 at once and its temporary files are gone."""
    import signal
    import subprocess
    import sys
    import time
    worker = subprocess.Popen([sys.executable, "-c", WORKER_IN_A_FINALIZER, str(tmp_path / "a.ply"),
                               str(tmp_path / "a.json")], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert worker.stdout.readline() == "ready\n"
    start = time.monotonic()
    worker.send_signal(signal.SIGTERM)
    _, err = worker.communicate(timeout=30)
    assert worker.returncode == 143, err
    assert time.monotonic() - start < 3  # not after the finalizer's 5 s
    assert list(tmp_path.iterdir()) == []


def test_sigterm_stops_a_study_at_once_keeps_the_finished_specimens_and_the_next_run_finishes_it(tmp_path):
    """A cluster's time limit sends SIGTERM: the running specimen stops, leaving no partial file, the ones not
    started are not run, the folder is unlocked, the finished ones are whole; the same command finishes the rest."""
    import signal
    import subprocess
    import sys
    import time
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(SAMPLE_MESHES / "cow.obj"))
    ms.meshing_surface_subdivision_midpoint(iterations=1)  # about 3 s a specimen with automatic pairs
    for name in ("cow_1", "cow_2", "cow_3"):
        ms.save_current_mesh(str(tmp_path / f"{name}.ply"))
    (tmp_path / "study.csv").write_text("mesh,pairs\ncow_1.ply,auto\ncow_2.ply,auto\ncow_3.ply,auto\n")
    outdir = tmp_path / "out"
    command = [sys.executable, "-m", "filter_symblend.commands", "batch", str(tmp_path / "study.csv"), "-o",
               str(outdir), "--workers", "1"]
    run = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 240
    while not (outdir / "cow_1.json").exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    run.send_signal(signal.SIGTERM)
    _, err = run.communicate(timeout=60)
    assert run.returncode == 143, err
    assert err.endswith(f"symblend: terminated; the specimens finished are in {outdir}, each whole, the others not "
                        "written (no partial file); the same command again finishes the rest\n")
    assert sorted(p.name for p in outdir.iterdir()) == ["cow_1.json", "cow_1.ply"]  # no partial file, no lock
    assert np.isfinite(_points(outdir / "cow_1.ply")).all()
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0 and "3 of 3 specimens symmetrized, 1 of them done before" in done.stdout
