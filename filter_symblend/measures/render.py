"""A picture of a before/after check: both meshes, coloured by mirror asymmetry, from three views (and the
output coloured by its uncertainty, when it has one).

The views are the object's own, decided by the output's mirror plane whatever the file's axes: along
the plane (left and right side by side), along the plane's normal (one side), and along the shape's
long axis in the plane (left and right side by side, end on). One colour scale serves both rows.

Needs matplotlib (the ``plot`` extra); everything else in the package works
without it. Faces are drawn back to front (painter's algorithm) after back-face
culling, each in the colour of its vertices' mean asymmetry, flat shaded.
"""

from __future__ import annotations

import numpy as np

from ..errors import SymblendError

# (title, the row of the plane frame the view looks along): rows are the normal, the long in-plane axis,
# and the in-plane axis across it. Looking along rows 2 and 1 puts the normal across the screen.
VIEWS = (("along the plane, left | right", 2), ("along the normal, one side", 0), ("along the long axis", 1))


def _plane_frame(points: np.ndarray, normal) -> np.ndarray:
    """Rows: the plane normal, then the in-plane principal axes (largest spread first)."""
    normal = np.asarray(normal, dtype=float)
    centred = points - points.mean(axis=0)
    in_plane = centred - np.outer(centred @ normal, normal)
    _, _, axes = np.linalg.svd(in_plane[:: max(1, len(points) // 20000)], full_matrices=False)
    return np.vstack([normal, axes[0], np.cross(normal, axes[0])])


def _draw(axis, mesh: dict, frame: np.ndarray, view_axis: int, colours) -> None:
    """``mesh`` (``points``, ``faces``, ``per_vertex``) seen along row ``view_axis`` of ``frame`` (3, 3), each
    triangle coloured by ``colours`` (values -> RGBA) of its corners' mean value."""
    from matplotlib.collections import PolyCollection

    points, faces, values = mesh["points"], mesh["faces"], mesh["per_vertex"]
    local = (points - points.mean(axis=0)) @ frame.T
    screen = [i for i in range(3) if i != view_axis]
    triangles = local[faces]
    facing = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])[:, view_axis] > 0
    depth = triangles[:, :, view_axis].mean(axis=1)
    order = np.argsort(depth)
    order = order[facing[order]] if facing.any() else order
    polygons = triangles[order][:, :, screen]
    shades = colours(values[faces[order]].mean(axis=1))
    axis.add_collection(PolyCollection(polygons, facecolors=shades, edgecolors=shades, linewidths=0.3))
    axis.set_xlim(local[:, screen[0]].min(), local[:, screen[0]].max())
    axis.set_ylim(local[:, screen[1]].min(), local[:, screen[1]].max())
    axis.set_aspect("equal")
    axis.axis("off")


def render_comparison(path, before: dict, after: dict, titles=("before", "after"),
                      uncertainty: dict | None = None) -> list[tuple[str, list]]:
    """Write a PNG: a row per mesh, a column per view, one shared colour bar (mesh units); with
    ``uncertainty`` a third row, the ``after`` mesh coloured by it on a colour bar of its own. The
    views look along the axes of the ``after`` mesh's symmetry frame (see the module docstring).

    ``before`` and ``after`` hold ``points`` (N, 3), ``faces`` (F, 3), ``per_vertex`` (N,)
    asymmetry, ``plane_normal`` (3,), and the summary's ``p90_relative`` and ``rms``; ``uncertainty``
    holds ``per_vertex`` (N,) (``symblend_uncertainty``, mesh units) and ``p90_relative``.
    Returns each view's title and the unit vector (3,) it looks along, in the meshes' frame.
    """
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise SymblendError("--png needs matplotlib, which is not installed: "
                            "pip install 'filter-symblend[plot]' (or pip install matplotlib).") from None
    top = max(before["max"], after["max"], 1e-12)  # the surfaces' (per_vertex holds stray vertices too)
    norm = matplotlib.colors.Normalize(0.0, top)
    colormap = matplotlib.colormaps["viridis"]
    rows = 2 if uncertainty is None else 3
    figure, axes = plt.subplots(rows, len(VIEWS), figsize=(5 * len(VIEWS), 4.5 * rows), constrained_layout=True)
    frame = _plane_frame(after["points"], after["plane_normal"])  # one frame: the same views of both
    for row, (mesh, title) in enumerate(zip((before, after), titles)):
        for column, (view, view_axis) in enumerate(VIEWS):
            _draw(axes[row, column], mesh, frame, view_axis, lambda values: colormap(norm(values)))
            figures = f"\np90 {mesh['p90_relative']:.3%} of the diagonal, RMS {mesh['rms']:.3g}"
            axes[row, column].set_title(f"{title}\n{view}" + (figures if column == 0 else ""), fontsize=9, wrap=True)
    bar = figure.colorbar(matplotlib.cm.ScalarMappable(norm, colormap), ax=axes[:2], shrink=0.6,
                          orientation="horizontal")
    bar.set_label("mirror asymmetry: distance to the reflected surface (mesh units)")
    if uncertainty is not None:
        spread = matplotlib.colors.Normalize(0.0, max(float(uncertainty["per_vertex"].max()), 1e-12))
        heat = matplotlib.colormaps["magma"]
        mesh = dict(after, per_vertex=uncertainty["per_vertex"])
        for column, (view, view_axis) in enumerate(VIEWS):
            _draw(axes[2, column], mesh, frame, view_axis, lambda values: heat(spread(values)))
            figures = f"\np90 {uncertainty['p90_relative']:.3%} of the diagonal"
            axes[2, column].set_title(f"{titles[1]}: uncertainty\n{view}" + (figures if column == 0 else ""),
                                      fontsize=9, wrap=True)
        bar = figure.colorbar(matplotlib.cm.ScalarMappable(spread, heat), ax=axes[2], shrink=0.6,
                              orientation="horizontal")
        bar.set_label("uncertainty: spread of each restored vertex, symblend_uncertainty (mesh units)")
    figure.savefig(path, dpi=100)
    plt.close(figure)
    return [(view, frame[view_axis].tolist()) for view, view_axis in VIEWS]
