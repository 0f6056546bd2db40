"""One symmetrization as a :class:`Problem` built and validated once (``build_problem``) and solved by
``solve_problem``; every door (the array API in ``filter_symblend.api``, the MeshSet filter in meshlab/,
the command through it) translates its medium into the problem and the result back."""

from .problem import MissingRegion, Problem, build_problem
from .run import solve_problem

__all__ = ["MissingRegion", "Problem", "build_problem", "solve_problem"]
