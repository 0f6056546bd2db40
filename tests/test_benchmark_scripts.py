"""The benchmark script stays runnable: its sections import, and the quickest one prints its table."""

import pathlib
import subprocess
import sys

SCRIPT = pathlib.Path(__file__).resolve().parents[1] / "scripts" / "benchmark.py"


def test_the_benchmark_runs_its_quickest_section_and_every_section_imports():
    done = subprocess.run([sys.executable, str(SCRIPT), "--pairs", "100", "--repeat", "1", "--meshes", "cow"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    rows = [line for line in done.stdout.splitlines() if line.startswith("| cow |")]
    assert [row.split(" | ")[1] for row in rows] == ["bend", "bend+compression", "articulated", "global affine"]
    # every mode made the bent cow more symmetric than it came in (input, baseline, three modes: shape / sym)
    for row in rows:
        cells = row.split(" | ")
        symmetry = [float(cell.split(" / ")[1]) for cell in cells[3:8]]
        assert all(value < symmetry[0] for value in symmetry[1:])
