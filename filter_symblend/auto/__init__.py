"""Automatic mirror pairs: a layer above the paper's method that finds the pairs on the surface itself.

``symmetrize_automatic`` runs the rounds (see :mod:`.rounds`); ``AutoConfig`` holds what
stays tunable. The pairs it finds go through the same checks and the same solve as a
user's landmarks (:mod:`filter_symblend.core.symmetrize`).
"""

from .config import DEFAULT, AutoConfig
from .rounds import symmetrize_automatic

__all__ = ["DEFAULT", "AutoConfig", "symmetrize_automatic"]
