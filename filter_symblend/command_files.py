"""Files of the ``symblend`` command checked before any work: where outputs go, and whether a mesh
loaded whole."""

from __future__ import annotations

import os
import pathlib

import numpy as np

from .errors import SymblendError

# Extensions pymeshlab writes (tests/test_cli.py saves a mesh in each).
MESH_SAVE_FORMATS = ("3ds", "ctm", "dae", "e57", "idtf", "json", "nxs", "nxz", "obj", "off", "ply", "stl",
                     "wrl", "x3d", "xyz")


def check_output_path(path: pathlib.Path, inputs: list[pathlib.Path], overwrite: bool, what: str,
                      formats: tuple[str, ...] | None = None) -> None:
    """Raise SymblendError unless ``path`` can take the ``what`` output (e.g. "output mesh"): not a folder,
    its folder exists and is writable, its extension one of ``formats`` (any without), and not one of
    ``inputs`` unless ``overwrite``."""
    if path.is_dir():
        raise SymblendError(f"{path}: is a folder; give the {what} a file name (in that folder, if you like).")
    folder = path.parent
    if not folder.is_dir():
        raise SymblendError(f"{path}: the folder {folder} does not exist; create it first.")
    if not os.access(folder, os.W_OK):
        raise SymblendError(f"{path}: the folder {folder} is not writable.")
    if formats is not None and path.suffix.lower().lstrip(".") not in formats:
        found = f"the extension {path.suffix!r}" if path.suffix else "no extension"
        raise SymblendError(f"{path}: {found}; the {what} needs one pymeshlab writes: "
                            f"{', '.join('.' + f for f in formats)} (.ply keeps quality and attributes).")
    for source in filter(None, inputs):
        if source.exists() and path.exists() and path.resolve() == source.resolve() and not overwrite:
            raise SymblendError(f"{path}: is the input file; choose another output, or add --overwrite to "
                                "replace it (it is replaced only once everything succeeded).")


def _header_counts(path: pathlib.Path) -> tuple[int | None, int | None]:
    """(vertices, faces) that a PLY, OFF or OBJ file declares (None where it does not say)."""
    suffix = path.suffix.lower()
    with open(path, "rb") as handle:
        if suffix == ".ply":
            counts = {}
            for raw in handle:
                words = raw.split()
                if words[:1] == [b"element"] and len(words) == 3:
                    counts[words[1].decode(errors="replace")] = int(words[2])
                if words[:1] == [b"end_header"]:
                    break
            return counts.get("vertex"), counts.get("face")
        if suffix == ".off":
            for raw in handle:
                words = raw.split(b"#")[0].split()
                if not words or words[0].upper().endswith(b"OFF") and len(words) == 1:
                    continue
                words = [w for w in words if not w.upper().endswith(b"OFF")]
                return int(words[0]), int(words[1])
        if suffix == ".obj":
            vertices = faces = 0
            for raw in handle:
                if raw.startswith(b"v "):
                    vertices += 1
                elif raw.startswith(b"f "):
                    faces += 1
            return vertices, faces
    return None, None


def check_loaded_mesh(path: pathlib.Path, points: np.ndarray, faces: np.ndarray) -> None:
    """Raise SymblendError when the mesh loaded from ``path`` is not the whole file: non-finite coordinates,
    fewer vertices than the file declares (pymeshlab drops a vertex `nan nan nan` and renumbers the rest,
    so landmarks by index would land on the wrong vertices), or fewer faces than it declares."""
    bad = np.flatnonzero(~np.isfinite(points).all(axis=1))
    if bad.size:
        raise SymblendError(f"{path}: vertex {bad[0]} has non-finite coordinates ({bad.size} such vertices); "
                            "repair the mesh (e.g. remove those vertices in MeshLab) first.")
    try:
        declared_vertices, declared_faces = _header_counts(path)
    except (OSError, ValueError, IndexError):
        return  # a header we cannot read: pymeshlab read the file, trust it
    if declared_vertices is not None and declared_vertices != len(points):
        raise SymblendError(f"{path}: the file declares {declared_vertices} vertices and {len(points)} could be "
                            "read (a vertex with non-finite coordinates, or a damaged file); the vertices would be "
                            "renumbered, so repair the mesh first.")
    if declared_faces is not None and len(faces) < declared_faces:
        raise SymblendError(f"{path}: the file declares {declared_faces} faces and only {len(faces)} could be read "
                            "(faces that refer to missing vertices, or a damaged file); repair the mesh first.")
