"""The thin-plate spline that carries the mesh, exact at the landmarks: the dense spline, the planar one
and the approximation for many landmarks (splines), the same dense spline by a preconditioned iteration
(iterative), and the choice among them by the number of landmarks (choice, :func:`thin_plate_spline`)."""

from .choice import thin_plate_spline

__all__ = ["thin_plate_spline"]
