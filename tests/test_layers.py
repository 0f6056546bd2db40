"""The package's floors: each imports only from the floors below it, no folder's modules import in a
circle (import-linter, the contracts in pyproject.toml), and the floors under meshlab/ run without
pymeshlab."""

import pathlib
import subprocess
import sys
import textwrap

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_every_import_contract_is_kept():
    run = subprocess.run([str(pathlib.Path(sys.executable).with_name("lint-imports")), "--no-cache"],
                         capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "Contracts: 3 kept, 0 broken." in run.stdout


def test_the_array_api_runs_without_pymeshlab():
    """A bent symmetric mesh, symmetrized from landmark pairs on arrays, with pymeshlab unimportable."""
    program = textwrap.dedent("""
        import sys
        sys.modules["pymeshlab"] = None  # import pymeshlab now raises ImportError
        import numpy as np
        import filter_symblend
        from filter_symblend import synthetic

        points, faces = synthetic.icosphere(3)
        points = synthetic.bumpy(points)
        offset, partner = synthetic.mirror_partners(points)
        left, right = synthetic.farthest_point_pairs(points, offset, partner, 40)
        bent = synthetic.bend(points, 0.5)
        result = filter_symblend.symmetrize(bent, left, right, faces=faces)
        every = np.flatnonzero(partner != np.arange(len(points)))
        before = synthetic.symmetry_error(bent, every, partner[every])
        after = synthetic.symmetry_error(result.points, every, partner[every])
        assert after < 0.05 * before, (before, after)
        assert not hasattr(filter_symblend, "generate_symmetrized_mesh")
        assert "filter_symblend.meshlab.meshset_filter" not in sys.modules
        print("ok", before, after)
    """)
    run = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0 and run.stdout.startswith("ok"), run.stderr
