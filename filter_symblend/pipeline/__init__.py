"""``filter_symblend.symmetrize`` on arrays: a :class:`Problem` built and validated once
(``build_problem``), solved by ``solve_problem``; the adapters above (meshlab/, commands/) translate their
medium into the problem and the result back."""

from .problem import Problem, build_problem
from .run import find_mirror_pairs, solve_problem, symmetrize

__all__ = ["Problem", "build_problem", "find_mirror_pairs", "solve_problem", "symmetrize"]
