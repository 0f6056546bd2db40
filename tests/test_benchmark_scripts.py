"""The benchmark script stays runnable: its sections import, and the quickest one prints its table."""

import pathlib
import subprocess
import sys

import pytest

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


def test_the_mirror_map_benchmark_finds_the_dataset_in_each_layout_and_names_a_wrong_path(tmp_path, monkeypatch):
    sys.path.insert(0, str(SCRIPT.parent))
    from benchmarks.mirror_maps import find_dataset
    monkeypatch.delenv("BCICP_DATASET", raising=False)
    unpacked, fetched = tmp_path / "unpacked", tmp_path / "fetched"
    (unpacked / "Dataset").mkdir(parents=True)
    (fetched / "repo").mkdir(parents=True)
    (fetched / "repo" / "HEAD").write_text("ref: refs/heads/master\n")
    assert find_dataset(str(unpacked)).root == unpacked and not find_dataset(str(unpacked)).git
    assert find_dataset(str(fetched)).root == fetched / "repo" and find_dataset(str(fetched)).git
    monkeypatch.setenv("BCICP_DATASET", str(fetched))
    assert find_dataset(None).root == fetched / "repo"
    monkeypatch.setenv("BCICP_DATASET", str(tmp_path / "nowhere"))
    with pytest.raises(ValueError, match=r"^\$BCICP_DATASET = .*nowhere holds no BCICP dataset: give an unpacked copy"):
        find_dataset(None)
    done = subprocess.run([sys.executable, str(SCRIPT), "--mirror-maps", "--bcicp", str(tmp_path)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 1 and "Traceback" not in done.stderr
    assert f"error: --bcicp = {tmp_path} holds no BCICP dataset" in done.stderr
