"""Read a PLY file's extra per-vertex properties back as custom attributes.

pymeshlab's PLY loader drops properties it does not know (PyMeshLab#385), but
it keeps the vertex order, so the values can be re-attached by index.
"""

from __future__ import annotations

import pathlib

import numpy as np

from ..errors import SymblendError

PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
             "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
             "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}
# Properties MeshLab reads itself: never re-attached as custom attributes.
KNOWN_PROPERTIES = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha", "quality",
                    "confidence", "radius", "texture_u", "texture_v", "s", "t", "u", "v", "flags"}


def read_ply_vertex_properties(path) -> dict[str, np.ndarray]:
    """Every scalar vertex property of a PLY file, as float arrays (N,), by name."""
    path = pathlib.Path(path)
    with path.open("rb") as handle:
        if handle.readline().strip() != b"ply":
            raise SymblendError(f"{path}: not a PLY file.")
        encoding, elements, current = None, [], None
        while True:
            line = handle.readline()
            if not line:
                raise SymblendError(f"{path}: the PLY header has no end_header line.")
            words = line.decode("ascii", "replace").split()
            if not words or words[0] in ("comment", "obj_info"):
                continue
            if words[0] == "end_header":
                break
            if words[0] == "format":
                encoding = words[1]
            elif words[0] == "element":
                current = (words[1], int(words[2]), [])
                elements.append(current)
            elif words[0] == "property" and current is not None:
                current[2].append(words[1:])
        body_start = handle.tell()
    if not elements or elements[0][0] != "vertex":
        raise SymblendError(f"{path}: the vertex element must come first in the PLY file.")
    _, count, properties = elements[0]
    if any(p[0] == "list" for p in properties):
        raise SymblendError(f"{path}: list properties on vertices are not supported.")
    names = [p[1] for p in properties]
    if encoding == "ascii":
        with path.open("rb") as handle:
            handle.seek(body_start)
            rows = np.loadtxt(handle, max_rows=count, ndmin=2)
        return {name: rows[:, i].astype(float) for i, name in enumerate(names)}
    order = {"binary_little_endian": "<", "binary_big_endian": ">"}.get(encoding)
    if order is None:
        raise SymblendError(f"{path}: unknown PLY format {encoding!r}.")
    dtype = np.dtype([(p[1], order + PLY_TYPES[p[0]]) for p in properties])
    data = np.fromfile(path, dtype=dtype, count=count, offset=body_start)
    return {name: data[name].astype(float) for name in names}


def load_mesh_with_attributes(ms, path) -> list[str]:
    """``ms.load_new_mesh(path)``, then, for a PLY file, the extra vertex properties as custom
    scalar attributes on the new mesh. Returns the names re-attached."""
    ms.load_new_mesh(str(path))
    if pathlib.Path(path).suffix.lower() != ".ply":
        return []
    mesh = ms.current_mesh()
    attached = []
    for name, values in read_ply_vertex_properties(path).items():
        if name.lower() not in KNOWN_PROPERTIES and len(values) == mesh.vertex_number():
            mesh.add_vertex_custom_scalar_attribute(values, name)
            attached.append(name)
    return attached
