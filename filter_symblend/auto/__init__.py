"""Automatic mirror pairs: a layer above the paper's method that finds the pairs on the surface itself.

``solve_with_automatic_pairs`` runs the rounds (see :mod:`.rounds`); ``AutoConfig`` holds what
stays tunable. The pairs it finds go through the same checks and the same solve as a
user's landmarks (:mod:`filter_symblend.core.solve`).
"""

from .config import DEFAULT, AutoConfig
from .rounds import solve_with_automatic_pairs

__all__ = ["DEFAULT", "AutoConfig", "solve_with_automatic_pairs"]
