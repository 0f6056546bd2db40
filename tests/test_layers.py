"""The package's floors: each imports only from the floors below it, no folder's modules import in a
circle, the package root reaches nothing of the command line (import-linter, the contracts in
pyproject.toml); the floors under meshlab/ run without pymeshlab and do not load it; importing the
package binds the filter onto MeshSet whenever pymeshlab loads."""

import pathlib
import subprocess
import sys
import textwrap

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_every_import_contract_is_kept():
    run = subprocess.run([str(pathlib.Path(sys.executable).with_name("lint-imports")), "--no-cache"],
                         capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stdout + run.stderr
    assert "Contracts: 4 kept, 0 broken." in run.stdout


def test_the_array_api_runs_without_pymeshlab():
    """A bent symmetric mesh, symmetrized from landmark pairs on arrays, with pymeshlab unimportable."""
    program = textwrap.dedent("""
        import sys
        sys.modules["pymeshlab"] = None  # import pymeshlab now raises ImportError
        import numpy as np
        import filter_symblend
        from filter_symblend.testing import synthetic

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
        try:
            filter_symblend.apply_filter_script
        except AttributeError as error:
            assert "needs pymeshlab, which is not installed here: pip install pymeshlab" in str(error), error
        else:
            raise AssertionError("apply_filter_script without pymeshlab")
        assert "filter_symblend.meshlab.meshset_filter" not in sys.modules
        print("ok", before, after)
    """)
    run = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0 and run.stdout.startswith("ok"), run.stderr


def _fresh(program: str) -> str:
    run = subprocess.run([sys.executable, "-c", textwrap.dedent(program)], capture_output=True, text=True,
                         cwd=ROOT)
    assert run.returncode == 0, run.stderr
    return run.stdout


def test_the_array_floors_do_not_load_pymeshlab():
    """The issue's check, and the same for the package root: pymeshlab loads only when someone asks."""
    _fresh("""
        import sys
        import filter_symblend.core
        assert "pymeshlab" not in sys.modules
        import filter_symblend, filter_symblend.api, filter_symblend.pipeline, filter_symblend.auto, filter_symblend.measures
        assert "pymeshlab" not in sys.modules
    """)


def test_importing_the_package_binds_the_filter_before_or_after_pymeshlab():
    for program in ("import pymeshlab\nimport filter_symblend\n",
                    "import filter_symblend\nimport pymeshlab\n",
                    "import filter_symblend.core\nfrom pymeshlab import MeshSet as _\nimport filter_symblend\n"
                    "import pymeshlab\n"):
        out = _fresh(program + """
ms = pymeshlab.MeshSet()
ms.add_mesh(pymeshlab.Mesh(vertex_matrix=[[0., 0, 0], [1, 0, 0], [0, 1, 0]], face_matrix=[[0, 1, 2]]))
print(ms.generate_symmetrized_mesh.__qualname__, type(pymeshlab.__loader__).__module__)
print(filter_symblend.FILTER_NAME, filter_symblend.apply_filter_script.__module__)
""")
        assert out.split() == ["MeshSet.generate_symmetrized_mesh", pymeshlab_loader_module(),
                               "generate_symmetrized_mesh", "filter_symblend.meshlab.script_runner"], (program, out)


def pymeshlab_loader_module() -> str:
    """The module of the loader Python gives pymeshlab when nothing of ours is loaded (independent reference)."""
    return _fresh("import pymeshlab; print(type(pymeshlab.__loader__).__module__)").strip()
