"""``symblend batch MANIFEST.csv -o OUTDIR``, a whole study in one call: ``symblend symmetrize`` over the rows
of a manifest, locally or on a Dask cluster (:func:`run` is the same from Python).

The manifest is a CSV with a header: ``mesh`` (required), ``landmarks`` (optional), and any option of
``symblend symmetrize`` as a column (``mode``, ``pairs``, ``pair_table``, ``midline``, ...), which
overrides the study's defaults for that row. Paths are relative to the manifest's folder. Each row runs
exactly as ``symblend symmetrize`` does (the same checks and messages), in its own process, with BLAS
held to one thread; a failing row is reported and the others complete.
"""

from __future__ import annotations

import csv
import io
import json
import multiprocessing
import os
import pathlib
import signal
import sys
import time
import warnings

from threadpoolctl import threadpool_limits

from ..atomic import remove_partial_files, write_text
from ..errors import SymblendError
from ..landmarks.formats import Landmark, LandmarkSet, write_tps_study
from .shared.console import one_line, terminal_progress
from .shared.folder_lock import folder_lock
from .shared.manifest import OUTPUT_OPTIONS, Row, read_manifest
from .shared.mesh_io import load_mesh
from .shared.options import add_filter_options, add_landmark_options, add_missing_option, symmetrize_arguments
from .symmetrize import landmark_name, symmetrize_files

ASYMMETRY_FIELDS = ("landmark_asymmetry_before", "landmark_asymmetry_after", "mirror_asymmetry_before",
                    "mirror_asymmetry_after")  # report entries whose RMS (relative) the summary shows
SUMMARY_FIELDS = ("mesh", "status", "seconds", *ASYMMETRY_FIELDS, "confident_share", "uncertainty_p90",
                  "most_influential_pair", "probably_misplaced", "output", "error")
SCHEDULER_TIMEOUT = 30  # seconds to wait for a Dask scheduler to answer
EXIT_TERMINATED = 143  # a worker stopped by SIGTERM, as the command itself exits


def register(commands) -> None:
    """Add the command to ``commands`` (argparse subparsers)."""
    batch = commands.add_parser("batch", help="symmetrize every specimen of a manifest CSV (a study), locally or "
                                              "on a Dask cluster")
    batch.add_argument("manifest", type=pathlib.Path,
                       help="CSV with a header: mesh, optionally landmarks and any symmetrize option per row")
    batch.add_argument("-o", "--output", required=True, type=pathlib.Path, metavar="OUTDIR",
                       help="folder for <mesh stem>.ply/.json, summary.csv and landmarks.tps")
    batch.add_argument("--workers", type=int, default=None, metavar="N",
                       help="local processes (default: the cores), BLAS at one thread each")
    batch.add_argument("--scheduler", metavar="ADDRESS",
                       help="run on the Dask cluster at ADDRESS (tcp://host:8786); needs filter-symblend[cluster]")
    batch.add_argument("--force", action="store_true", help="redo rows whose outputs are newer than their inputs")
    batch.add_argument("--wait", action="store_true",
                       help="if another symblend batch is writing OUTDIR, wait for it to end (default: stop, saying "
                            "which run holds it)")
    add_landmark_options(batch, required=False, note=" (default for rows without a landmarks column)",
                         save_pair_table=False)
    add_missing_option(batch)
    add_filter_options(batch)
    batch.set_defaults(handler=run_command, parser=batch, stopped_leaves=lambda args: (
        f"the specimens finished are in {args.output}, each whole, the others not written (no partial file); the "
        "same command again finishes the rest"))


def run_command(args) -> int:
    """The command: the options given on its line are every row's defaults; exit status 1 if a row failed."""
    if args.workers is not None and args.workers < 1:
        raise SymblendError(f"--workers {args.workers}: give 1 or more processes.")
    defaults = []  # the options given on the command line, as words of symblend symmetrize
    for action in args.parser._actions:
        if not action.option_strings or action.dest in (*OUTPUT_OPTIONS, "manifest", "workers", "scheduler", "force", "wait"):
            continue
        value = getattr(args, action.dest)
        if value == action.default or value is None:
            continue
        defaults += [action.option_strings[-1]] if action.nargs == 0 else [action.option_strings[-1], str(value)]
    summaries = run(args.manifest, args.output, defaults, args.workers, args.scheduler, args.force,
                    progress=sys.stderr.isatty(), wait=args.wait)
    failed = [s for s in summaries if s["status"] == "failed"]
    print(f"{args.output}: {len(summaries) - len(failed)} of {len(summaries)} specimens symmetrized"
          + (f", {sum(s['status'] == 'done before' for s in summaries)} of them done before" if not args.force else "")
          + (f"; {len(failed)} failed (see summary.csv)" if failed else ""))
    return 1 if failed else 0


def run_row(row: Row) -> dict:
    """One specimen, as ``symblend symmetrize`` runs it: its summary row, and its landmark coordinates
    after symmetrizing (``"landmarks"``: [[name, x, y, z], ...]) for the study's TPS file."""
    start = time.perf_counter()
    summary = {"mesh": str(row.mesh), "output": str(row.output)}
    try:
        with threadpool_limits(1), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            done = symmetrize_files(symmetrize_arguments(list(row.arguments)))
    except Exception as error:  # noqa: BLE001  one specimen's failure, of any kind, must not stop the study
        if isinstance(error, SymblendError):
            message = one_line(error)
        elif isinstance(error, OSError):
            message = f"{error.filename}: {error.strerror}"
        else:
            message = f"unexpected {type(error).__name__}: {one_line(error)} (please report it)"
        return {**summary, "output": "", "status": "failed", "seconds": round(time.perf_counter() - start, 2),
                "error": message}  # no output: a failed row writes nothing
    return {**summary, "status": "ok", "seconds": round(time.perf_counter() - start, 2),
            **_from_saved(done.document, done.ms.current_mesh().vertex_matrix())}


def _from_saved(saved: dict, points) -> dict:
    """What a specimen's summary takes from its JSON report (the file's form, so that a row done now and one
    done by an earlier run read alike) and output points (N, 3): the asymmetry columns
    (RMS, relative to the diagonal), with automatic pairs the confident share of their map, with
    ``uncertainty`` its 90th percentile and the landmark names of the most influential pair and of a
    probably misplaced one, and its landmarks after symmetrizing ([[name, x, y, z], ...])."""
    figures = {key: f"{saved[key]['rms_relative']:.6g}" for key in ASYMMETRY_FIELDS if key in saved}
    if "auto_pairs" in saved:  # the share of the surface whose automatic twin is confident
        figures["confident_share"] = f"{saved['auto_pairs']['mirror_map']['confident_share']:.3g}"
    if "uncertainty" in saved:  # the spread's 90th percentile (relative) and the pair that moves it most
        figures["uncertainty_p90"] = f"{saved['uncertainty']['p90_relative']:.6g}"
        figures["most_influential_pair"] = landmark_name(saved["uncertainty"]["most_influential_pair"],
                                                         saved.get("landmarks"))
        misplaced = saved["uncertainty"].get("probably_misplaced")  # absent from reports of earlier versions
        if misplaced is not None:
            figures["probably_misplaced"] = landmark_name(misplaced, saved.get("landmarks"))
    placed = (saved.get("landmarks") or {}).get("vertices", [])
    return {**figures, "landmarks": [[name, *map(float, points[vertex])] for name, vertex in placed]}


def _done_before(row: Row) -> dict:
    """The summary of a row done by an earlier run, from its report."""
    saved = json.loads(row.report.read_text())
    ms = load_mesh(row.output)  # any file name (pymeshlab takes UTF-8 text only)
    return {"mesh": str(row.mesh), "output": str(row.output), "status": "done before", "seconds": 0.0,
            **_from_saved(saved, ms.current_mesh().vertex_matrix())}


def _stop_worker(signum, frame) -> None:
    """SIGTERM in a worker: its row's partial outputs removed, it exits at once."""
    remove_partial_files()
    os._exit(EXIT_TERMINATED)


def _start_worker() -> None:
    """A worker stops on SIGTERM (the batch stopped) and leaves Ctrl-C in the terminal to the batch."""
    signal.signal(signal.SIGTERM, _stop_worker)
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _row_and_summary(row: Row) -> tuple[Row, dict]:
    return row, run_row(row)


def _local(rows: list[Row], workers: int):
    """(row, summary) as each row completes, on a local pool of ``workers`` processes (each row holds BLAS
    to one thread, :func:`run_row`). When the batch stops (SIGTERM, Ctrl-C, an error), the workers stop
    their rows at once, leaving no partial file, and the rows not started are not run."""
    pool = multiprocessing.get_context("spawn").Pool(workers, initializer=_start_worker)
    try:
        yield from pool.imap_unordered(_row_and_summary, rows)
        pool.close()
    except BaseException:
        pool.terminate()
        raise
    finally:
        pool.join()


def _dask(rows: list[Row], scheduler: str):
    """(row, summary) as each row completes, on the Dask cluster at ``scheduler``."""
    try:
        from dask.distributed import Client
        from dask.distributed import as_completed as dask_completed
    except ImportError:
        raise SymblendError("--scheduler runs the rows on a Dask cluster, and dask.distributed is not installed; "
                            "pip install 'filter-symblend[cluster]'.") from None
    try:
        client = Client(scheduler, timeout=SCHEDULER_TIMEOUT)
    except (OSError, TimeoutError) as error:
        raise SymblendError(f"--scheduler {scheduler}: no Dask scheduler answers there ({error}).") from None
    with client:
        futures = client.map(run_row, rows, pure=False)
        by_key = {future.key: row for future, row in zip(futures, rows)}
        for future in dask_completed(futures):
            yield by_key[future.key], future.result()


def _write_summary(path: pathlib.Path, summaries: list[dict]) -> None:
    table = io.StringIO()
    writer = csv.DictWriter(table, SUMMARY_FIELDS, extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    writer.writerows(summaries)
    write_text(path, table.getvalue())


def _write_study_landmarks(path: pathlib.Path, summaries: list[dict]) -> None:
    study = {pathlib.Path(s["mesh"]).stem: LandmarkSet([Landmark(name, (x, y, z)) for name, x, y, z in s["landmarks"]])
             for s in summaries if s.get("landmarks")}
    if study:
        write_tps_study(path, study)


def run(manifest: str | os.PathLike, outdir: str | os.PathLike, defaults: list[str] = (), workers: int | None = None,
        scheduler: str | None = None, force: bool = False, progress: bool = False, wait: bool = False) -> list[dict]:
    """Symmetrize every row of ``manifest`` into ``outdir`` (see the module docstring).

    ``defaults``: ``symblend symmetrize`` option words for every row (e.g. ``["--mode", "affine"]``);
    ``workers``: local processes (default: the cores); ``scheduler``: a Dask scheduler address
    (``tcp://host:8786``) to run on instead; ``force``: redo rows whose output and report are newer than
    their inputs (skipped otherwise); ``wait``: if another batch is writing ``outdir``, wait for it to end
    instead of stopping (:mod:`.folder_lock`). Writes ``<mesh stem>.ply`` and ``.json`` per row, ``summary.csv``
    (one row per specimen, in manifest order) and ``landmarks.tps`` (the symmetrized landmarks of the
    study, one specimen per mesh stem). Returns the summary rows.
    """
    outdir = pathlib.Path(outdir)
    if not outdir.is_dir():
        if outdir.exists() or not outdir.parent.is_dir():
            raise SymblendError(f"{outdir}: give a folder for the outputs (its parent folder must exist).")
        outdir.mkdir()
    rows = read_manifest(manifest, outdir, list(defaults))
    with folder_lock(outdir, wait):
        return _run_rows(rows, outdir, workers, scheduler, force, progress)


def _run_rows(rows: list[Row], outdir: pathlib.Path, workers, scheduler, force: bool, progress: bool) -> list[dict]:
    """The rows run (those done before skipped unless ``force``), the summary and the study's landmarks written."""
    summaries = {row: _done_before(row) for row in rows if not force and row.done()}
    pending = [row for row in rows if row not in summaries]
    if pending:
        runs = _dask(pending, scheduler) if scheduler else _local(pending, workers or os.cpu_count() or 1)
        for done, (row, summary) in enumerate(runs, start=len(summaries) + 1):
            summaries[row] = summary
            if summary["status"] == "failed":
                print(f"symblend: {row.mesh.name}: {summary['error']}", file=sys.stderr)
            if progress:
                terminal_progress(100.0 * done / len(rows), f"{done}/{len(rows)} specimens, last: {row.mesh.name} "
                                                              f"{summary['status']}")
    ordered = [summaries[row] for row in rows]
    _write_summary(outdir / "summary.csv", ordered)
    _write_study_landmarks(outdir / "landmarks.tps", ordered)
    return ordered
