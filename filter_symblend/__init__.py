"""filter_symblend: symmetrize meshes from landmark pairs, as a pymeshlab filter.

Implements Ghosh, Amenta and Kazhdan, *Closed-form Blending of Local
Symmetries* (SGP 2010). Importing the package binds
``pymeshlab.MeshSet.generate_symmetrized_mesh``; ``apply_filter_script`` and
``save_filter_script`` run and record MeshLab filter scripts that use it.
Without pymeshlab, the array API (``symmetrize``, and everything under core/,
landmarks/, checks/ and auto/) still imports and runs.
"""

from .commands.start import quiet_interrupt_while_loading

quiet_interrupt_while_loading()  # acts only in the symblend command's own process

from .core.mirror_pairs import MirrorPairs
from .core.symmetrize import SymmetrizationResult
from .errors import (GeometryError, LandmarkError, MeshSetError, ParameterError, SymblendError,
                     SymblendWarning, SymmetryNotFoundError)
from .landmarks.from_file import pairs_from_landmark_file
from .parameters import PARAMETERS
from .pipeline import find_mirror_pairs, symmetrize

__all__ = [
    "PARAMETERS", "GeometryError", "LandmarkError", "MeshSetError", "MirrorPairs", "ParameterError", "SymblendError",
    "SymblendWarning", "SymmetrizationResult", "SymmetryNotFoundError", "find_mirror_pairs", "pairs_from_landmark_file",
    "symmetrize",
]

try:
    from .meshlab.meshset_filter import (ASYMMETRY_ATTRIBUTE, CONFIDENCE_ATTRIBUTE, DISPLAY_NAME, FILTER_NAME,
                                         TWIN_ATTRIBUTE, UNCERTAINTY_ATTRIBUTE, bind_to_meshset,
                                         generate_symmetrized_mesh)
    from .meshlab.mlx import ScriptError
    from .meshlab.script_runner import apply_filter_script, save_filter_script
except ImportError as error:
    if error.name != "pymeshlab":  # without pymeshlab, the array API above still works: anything else is a bug
        raise
else:
    bind_to_meshset()
    __all__ += ["ASYMMETRY_ATTRIBUTE", "CONFIDENCE_ATTRIBUTE", "DISPLAY_NAME", "FILTER_NAME", "ScriptError",
                "TWIN_ATTRIBUTE", "UNCERTAINTY_ATTRIBUTE", "apply_filter_script", "generate_symmetrized_mesh",
                "save_filter_script"]
