"""A picture of a before/after check: both meshes, coloured by mirror asymmetry, from three views.

Needs matplotlib (the ``plot`` extra); everything else in the package works
without it. Faces are drawn back to front (painter's algorithm) after back-face
culling, each in the colour of its vertices' mean asymmetry, flat shaded.
"""

from __future__ import annotations

import numpy as np

from ..errors import SymblendError

VIEWS = (("front", 2), ("top", 1), ("side", 0))  # looking along this axis of the plane frame


def _plane_frame(points: np.ndarray, normal) -> np.ndarray:
    """Rows: the plane normal, then the in-plane principal axes (largest spread first)."""
    normal = np.asarray(normal, dtype=float)
    centred = points - points.mean(axis=0)
    in_plane = centred - np.outer(centred @ normal, normal)
    _, _, axes = np.linalg.svd(in_plane[:: max(1, len(points) // 20000)], full_matrices=False)
    return np.vstack([normal, axes[0], np.cross(normal, axes[0])])


def _draw(axis, points, faces, values, frame, view_axis, norm, colormap):
    from matplotlib.collections import PolyCollection

    local = (points - points.mean(axis=0)) @ frame.T
    screen = [i for i in range(3) if i != view_axis]
    triangles = local[faces]
    facing = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])[:, view_axis] > 0
    depth = triangles[:, :, view_axis].mean(axis=1)
    order = np.argsort(depth)
    order = order[facing[order]] if facing.any() else order
    polygons = triangles[order][:, :, screen]
    colours = colormap(norm(values[faces[order]].mean(axis=1)))
    axis.add_collection(PolyCollection(polygons, facecolors=colours, edgecolors=colours, linewidths=0.3))
    axis.set_xlim(local[:, screen[0]].min(), local[:, screen[0]].max())
    axis.set_ylim(local[:, screen[1]].min(), local[:, screen[1]].max())
    axis.set_aspect("equal")
    axis.axis("off")


def render_comparison(path, before: dict, after: dict, titles=("before", "after")) -> None:
    """Write a PNG: a row per mesh, a column per view, one shared colour bar (mesh units). The
    views look along the axes of the ``after`` mesh's symmetry frame.

    ``before`` and ``after`` hold ``points`` (N, 3), ``faces`` (F, 3),
    ``per_vertex`` (N,) asymmetry and ``plane_normal`` (3,).
    """
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise SymblendError("--png needs matplotlib, which is not installed: "
                            "pip install 'filter-symblend[plot]' (or pip install matplotlib).") from None
    top = max(float(before["per_vertex"].max()), float(after["per_vertex"].max()), 1e-12)
    norm = matplotlib.colors.Normalize(0.0, top)
    colormap = matplotlib.colormaps["viridis"]
    figure, axes = plt.subplots(2, len(VIEWS), figsize=(4 * len(VIEWS), 7.5), constrained_layout=True)
    frame = _plane_frame(after["points"], after["plane_normal"])  # one frame: the same views of both
    for row, (mesh, title) in enumerate(zip((before, after), titles)):
        for column, (view, view_axis) in enumerate(VIEWS):
            _draw(axes[row, column], mesh["points"], mesh["faces"], mesh["per_vertex"], frame, view_axis,
                  norm, colormap)
            axes[row, column].set_title(f"{title}: {view}  (RMS {mesh['rms']:.3g})" if column == 0 else view)
    bar = figure.colorbar(matplotlib.cm.ScalarMappable(norm, colormap), ax=axes, shrink=0.8)
    bar.set_label("mirror asymmetry: distance to the reflected surface (mesh units)")
    figure.savefig(path, dpi=100)
    plt.close(figure)
