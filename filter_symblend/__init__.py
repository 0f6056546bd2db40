"""filter_symblend: symmetrize meshes from landmark pairs, as a pymeshlab filter.

Implements Ghosh, Amenta and Kazhdan, *Closed-form Blending of Local
Symmetries* (SGP 2010). Importing the package binds
``pymeshlab.MeshSet.generate_symmetrized_mesh`` (now if pymeshlab is loaded,
else as soon as it is); ``apply_filter_script`` and ``save_filter_script``
run and record MeshLab filter scripts that use it. The array API
(``symmetrize`` and ``find_mirror_pairs`` from api.py, and everything under
core/, landmarks/, measures/, auto/ and pipeline/) imports and runs without
pymeshlab, and does not load it.
"""

import importlib

from .api import find_mirror_pairs, symmetrize
from .core.mirror_pairs import MirrorPairs
from .core.report import Report
from .core.solve import SymmetrizationResult
from .errors import (GeometryError, LandmarkError, MeshSetError, ParameterError, SymblendError,
                     SymblendWarning, SymmetryNotFoundError)
from .landmarks.from_file import pairs_from_landmark_file
from .meshlab.when_imported import bind_when_pymeshlab_imported
from .parameters import PARAMETERS

bind_when_pymeshlab_imported()

_MESHLAB_NAMES = {  # loaded on first use, with pymeshlab
    "ASYMMETRY_ATTRIBUTE": "meshset_filter", "CONFIDENCE_ATTRIBUTE": "meshset_filter",
    "DISPLAY_NAME": "meshset_filter", "FILTER_NAME": "meshset_filter", "TWIN_ATTRIBUTE": "meshset_filter",
    "UNCERTAINTY_ATTRIBUTE": "meshset_filter", "generate_symmetrized_mesh": "meshset_filter",
    "ScriptError": "filter_script", "apply_filter_script": "script_runner", "save_filter_script": "script_runner",
}

__all__ = [
    "PARAMETERS", "GeometryError", "LandmarkError", "MeshSetError", "MirrorPairs", "ParameterError", "Report",
    "SymblendError",
    "SymblendWarning", "SymmetrizationResult", "SymmetryNotFoundError", "find_mirror_pairs", "pairs_from_landmark_file",
    "symmetrize", *sorted(_MESHLAB_NAMES),
]


def __getattr__(name):
    if name not in _MESHLAB_NAMES:
        raise AttributeError(f"module 'filter_symblend' has no attribute {name!r}")
    try:
        module = importlib.import_module(f".meshlab.{_MESHLAB_NAMES[name]}", __name__)
    except ImportError as error:
        if error.name != "pymeshlab":
            raise
        raise AttributeError(f"filter_symblend.{name} needs pymeshlab, which is not installed here: "
                             "pip install pymeshlab") from error
    value = getattr(module, name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_MESHLAB_NAMES))
