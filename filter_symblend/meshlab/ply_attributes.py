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
    """Every vertex property of a PLY file, by name, as float arrays: (N,) for a scalar, (N, k) for a list of
    one length k on every vertex (a custom point attribute: k = 3)."""
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
    if encoding == "ascii":
        with path.open("rb") as handle:
            handle.seek(body_start)
            rows = np.loadtxt(handle, max_rows=count, ndmin=2)
        return _columns(path, properties, rows)
    order = {"binary_little_endian": "<", "binary_big_endian": ">"}.get(encoding)
    if order is None:
        raise SymblendError(f"{path}: unknown PLY format {encoding!r}.")
    # A list property (MeshLab writes a custom point attribute as one of 3 doubles) has a fixed length when
    # every vertex's count equals the first vertex's: read that count, then every record with it.
    fields, offset = [], body_start
    with path.open("rb") as handle:
        for number, p in enumerate(properties):
            if p[0] == "list":
                handle.seek(offset)
                length_type = np.dtype(order + PLY_TYPES[p[1]])
                length = int(np.frombuffer(handle.read(length_type.itemsize), dtype=length_type)[0])
                fields += [(f"_count{number}", length_type), (p[3], order + PLY_TYPES[p[2]], (length,))]
            else:
                fields.append((p[1], order + PLY_TYPES[p[0]]))
            offset = body_start + np.dtype(fields).itemsize
    data = np.fromfile(path, dtype=np.dtype(fields), count=count, offset=body_start)
    for number, p in enumerate(properties):
        if p[0] == "list" and np.any(data[f"_count{number}"] != data[f"_count{number}"][0]):
            raise _varying_length(path, p[3])
    return {p[-1]: data[p[-1]].astype(float) for p in properties}


def _varying_length(path, name: str) -> SymblendError:
    return SymblendError(f"{path}: the vertex property {name!r} is a list of varying length; only lists of one "
                         "length (such as a point attribute's 3 coordinates) are read.")


def _columns(path, properties, rows: np.ndarray) -> dict[str, np.ndarray]:
    """The properties of an ASCII PLY's vertex ``rows`` (N, columns): scalars (N,), lists of one length (N, k)."""
    out, column = {}, 0
    for p in properties:
        if p[0] == "list":
            length = int(rows[0, column])
            if np.any(rows[:, column] != length):
                raise _varying_length(path, p[3])
            out[p[3]] = rows[:, column + 1:column + 1 + length].astype(float)
            column += 1 + length
        else:
            out[p[1]] = rows[:, column].astype(float)
            column += 1
    return out


def load_mesh_with_attributes(ms, path) -> list[str]:
    """``ms.load_new_mesh(path)``, then, for a PLY file, the extra vertex properties as custom attributes
    on the new mesh: scalars as scalar attributes, lists of 3 as point attributes (others are left out).
    Returns the names re-attached."""
    ms.load_new_mesh(str(path))
    if pathlib.Path(path).suffix.lower() != ".ply":
        return []
    mesh = ms.current_mesh()
    attached = []
    for name, values in read_ply_vertex_properties(path).items():
        if name.lower() in KNOWN_PROPERTIES or len(values) != mesh.vertex_number():
            continue
        if values.ndim == 1:
            mesh.add_vertex_custom_scalar_attribute(values, name)
        elif values.shape[1] == 3:
            mesh.add_vertex_custom_point_attribute(values, name)
        else:
            continue
        attached.append(name)
    return attached
