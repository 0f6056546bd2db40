"""filter_symblend: symmetrize meshes from landmark pairs, as a pymeshlab filter.

Implements Ghosh, Amenta and Kazhdan, *Closed-form Blending of Local
Symmetries* (SGP 2010). Importing the package binds
``pymeshlab.MeshSet.generate_symmetrized_mesh``; ``apply_filter_script`` and
``save_filter_script`` run and record MeshLab filter scripts that use it.
"""

from .command_start import quiet_interrupt_while_loading

quiet_interrupt_while_loading()

from .errors import (GeometryError, LandmarkError, MeshSetError, ParameterError, SymblendError,
                     SymblendWarning, SymmetryNotFoundError)
from .meshlab.meshset_filter import (ASYMMETRY_ATTRIBUTE, DISPLAY_NAME, FILTER_NAME, bind_to_meshset,
                             generate_symmetrized_mesh)
from .meshlab.mlx import ScriptError
from .landmarks.from_file import pairs_from_landmark_file
from .parameters import PARAMETERS
from .meshlab.script_runner import apply_filter_script, save_filter_script
from .pipeline import symmetrize
from .core.symmetrize import SymmetrizationResult

bind_to_meshset()

__all__ = [
    "ASYMMETRY_ATTRIBUTE", "DISPLAY_NAME", "FILTER_NAME", "PARAMETERS", "GeometryError",
    "LandmarkError", "MeshSetError", "ParameterError", "ScriptError", "SymblendError", "SymblendWarning",
    "SymmetrizationResult", "SymmetryNotFoundError", "apply_filter_script", "generate_symmetrized_mesh",
    "pairs_from_landmark_file", "save_filter_script", "symmetrize",
]
