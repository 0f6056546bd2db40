"""The ``symblend`` command's files: outputs checked before any work, meshes loaded whole (PLY attributes
included), and every output written under a temporary name, then renamed."""

from __future__ import annotations

import contextlib
import json
import os
import pathlib
import shutil
from collections.abc import Iterator

import numpy as np
import pymeshlab

from ...atomic import all_or_none
from ...errors import SymblendError
from ...meshlab.attributes import custom_attribute_names
from ...meshlab.ply_attributes import load_mesh_with_attributes
from .console import one_line

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


OBJ_DATA = (b"v", b"vn", b"vt", b"f")  # OBJ statements that carry the mesh


def _cut_short(path: pathlib.Path, faces_read: int) -> str | None:
    """The last line of an OBJ file (which declares no counts) when the file looks cut in the middle of it: no
    final newline after a data line, and no face read (a copy stopped inside the vertices); or None."""
    if path.suffix.lower() != ".obj" or faces_read:
        return None
    with open(path, "rb") as handle:
        handle.seek(max(0, path.stat().st_size - 256))
        tail = handle.read()
    if not tail or tail.endswith(b"\n"):
        return None
    last = tail.rsplit(b"\n", 1)[-1]
    words = last.split()
    return last.decode("ascii", "replace").strip() if words and words[0] in OBJ_DATA else None


def check_loaded_mesh(path: pathlib.Path, points: np.ndarray, faces: np.ndarray) -> None:
    """Raise SymblendError when the mesh loaded from ``path`` is not the whole file: non-finite coordinates,
    an OBJ that ends in the middle of a line, fewer vertices than the file declares (pymeshlab drops a vertex
    `nan nan nan` and renumbers the rest, so landmarks by index would land on the wrong vertices), or fewer
    faces than it declares."""
    bad = np.flatnonzero(~np.isfinite(points).all(axis=1))
    if bad.size:
        raise SymblendError(f"{path}: vertex {bad[0]} has non-finite coordinates ({bad.size} such vertices); "
                            "repair the mesh (e.g. remove those vertices in MeshLab) first.")
    try:
        declared_vertices, declared_faces = _header_counts(path)
        cut = _cut_short(path, len(faces))
    except (OSError, ValueError, IndexError):
        return  # a header we cannot read: pymeshlab read the file, trust it
    if cut is not None:
        raise SymblendError(f"{path}: the file ends in the middle of a line ('{cut}') and no face could be read: it "
                            f"looks cut short (a copy or a download that stopped); pymeshlab read {len(points)} "
                            "vertices of it. Copy the whole file again (a whole point cloud: end it with a newline).")
    if declared_vertices is not None and declared_vertices != len(points):
        raise SymblendError(f"{path}: the file declares {declared_vertices} vertices and {len(points)} could be "
                            "read (a vertex with non-finite coordinates, or a damaged file); the vertices would be "
                            "renumbered, so repair the mesh first.")
    if declared_faces is not None and len(faces) < declared_faces:
        raise SymblendError(f"{path}: the file declares {declared_faces} faces and only {len(faces)} could be read "
                            "(faces that refer to missing vertices, or a damaged file); repair the mesh first.")


def check_outputs(args, outputs: dict[str, pathlib.Path | None], inputs: list[pathlib.Path]) -> None:
    """Every output path of the command (``{what: path or None}``) checked before any work (see
    :func:`check_output_path`; ``args.overwrite`` if the command has it); two outputs may not share a file;
    each folder must have room for what is written to it (:func:`check_free_space`, the first input being
    the mesh)."""
    overwrite = getattr(args, "overwrite", False)
    given = {what: path for what, path in outputs.items() if path is not None}
    for what, path in given.items():
        check_output_path(path, inputs, overwrite, what, MESH_SAVE_FORMATS if what == "output mesh" else None)
    resolved = [path.resolve() for path in given.values()]
    for index, path in enumerate(resolved):
        if path in resolved[:index]:
            raise SymblendError(f"{list(given.values())[index]}: given for two outputs; give each its own file.")
    if inputs and inputs[0] is not None and inputs[0].is_file():
        check_free_space(given, inputs[0].stat().st_size)


# An output mesh takes at most about this many times the size of its input file. Measured: the cow as a
# binary PLY (145 kB) gives a 544 kB OBJ (text) and a 288 kB PLY with the automatic pairs' attributes.
MESH_SIZE_FACTOR = 4
MESH_OUTPUTS = ("output mesh", "distance mesh")
OTHER_OUTPUT_BYTES = 2**20  # a report, a landmark file, a picture


def check_free_space(outputs: dict[str, pathlib.Path], input_bytes: int) -> None:
    """SymblendError, before any work, when a file system has less free space than the ``outputs``
    (``{what: path}``) written to it need: MESH_SIZE_FACTOR x ``input_bytes`` for a mesh, a megabyte for
    anything else (all outputs are written under temporary names first, then renamed)."""
    needed, folders = {}, {}
    for what, path in outputs.items():
        folder = path.resolve().parent
        device = folder.stat().st_dev
        needed[device] = needed.get(device, 0) + (MESH_SIZE_FACTOR * input_bytes if what in MESH_OUTPUTS
                                                  else OTHER_OUTPUT_BYTES)
        folders.setdefault(device, folder)
    for device, need in needed.items():
        free = shutil.disk_usage(folders[device]).free
        if free < need:
            raise SymblendError(f"{folders[device]}: {free / 1e6:.1f} MB free, and the outputs written there need "
                                f"about {need / 1e6:.1f} MB (an output mesh up to {MESH_SIZE_FACTOR}x its input "
                                "file); free some space, or write the outputs to another disk.")


def _utf8(path: pathlib.Path) -> bool:
    """Whether pymeshlab (which takes UTF-8 text) can be given ``path``: a Linux file name is any bytes."""
    try:
        str(path).encode("utf-8")
        return True
    except UnicodeEncodeError:
        return False


def _ascii_sibling(path: pathlib.Path, purpose: str) -> pathlib.Path:
    """A hidden ASCII name beside ``path``, with its suffix (pymeshlab goes by it), for this process."""
    return path.with_name(f".symblend-{purpose}-{os.getpid()}{path.suffix.encode('ascii', 'ignore').decode()}")


@contextlib.contextmanager
def _readable_name(path: pathlib.Path) -> Iterator[pathlib.Path]:
    """``path``, or when pymeshlab cannot take its name, a link to it with an ASCII name in the same folder
    (an OBJ's material and texture files are found beside it), removed afterwards."""
    if _utf8(path):
        yield path
        return
    alias = _ascii_sibling(path, "reading")
    os.symlink(path.resolve(), alias)
    try:
        yield alias
    finally:
        alias.unlink(missing_ok=True)


def load_mesh(path: pathlib.Path, ms: pymeshlab.MeshSet | None = None) -> pymeshlab.MeshSet:
    """``path`` loaded as a new layer of ``ms`` (a new MeshSet by default), PLY attributes included; any
    file name the file system accepts."""
    if not path.exists():
        raise SymblendError(f"{path}: no such mesh file.")
    if not path.is_file():
        raise SymblendError(f"{path}: not a regular file (a folder, a pipe or a device); give a mesh file.")
    ms = pymeshlab.MeshSet() if ms is None else ms
    try:
        with _readable_name(path) as readable:
            load_mesh_with_attributes(ms, readable)
    except pymeshlab.PyMeshLabException as error:
        raise SymblendError(f"{path}: pymeshlab cannot read it ({one_line(error)}).") from None
    check_loaded_mesh(path, ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix())
    return ms


def save_mesh(ms: pymeshlab.MeshSet, path: pathlib.Path, output: pathlib.Path | None = None) -> None:
    """Save the current mesh to ``path`` (a temporary name for ``output``, whose name messages give). A PLY
    keeps quality and every custom per-vertex attribute (scalars, and points such as the automatic pairs'
    twins)."""
    output = output or path
    options = {}
    if output.suffix.lower() == ".ply":
        names = custom_attribute_names(ms)
        options = {"save_vertex_quality": True, **{f"__ca_{kind}__{name}": True for kind in ("vs", "vp")
                                                   for name in names[kind]}}
    try:
        if _utf8(path):
            ms.save_current_mesh(str(path), **options)
        else:  # pymeshlab writes an ASCII name beside it, renamed to ``path``
            ascii_name = _ascii_sibling(path, "writing")
            try:
                ms.save_current_mesh(str(ascii_name), **options)
                os.replace(ascii_name, path)
            finally:
                ascii_name.unlink(missing_ok=True)
    except pymeshlab.PyMeshLabException as error:
        raise SymblendError(f"{output}: pymeshlab cannot write it ({one_line(error)}; is the disk full?).") from None


def save_with_report(ms: pymeshlab.MeshSet, output: pathlib.Path, report_path: pathlib.Path | None,
                     report: dict) -> None:
    """The output mesh and its JSON report (if ``report_path``), both written or neither."""
    text = None if report_path is None else report_json(report)  # any fault of the report's before any write
    with all_or_none([output, report_path]) as (mesh_temporary, report_temporary):
        save_mesh(ms, mesh_temporary, output)
        if report_temporary is not None:
            report_temporary.write_text(text, encoding="utf-8")


def save_quality_ply(ms: pymeshlab.MeshSet, path: pathlib.Path, quality: np.ndarray,
                     output: pathlib.Path | None = None) -> None:
    """Save the current mesh of ``ms`` to ``path`` (a temporary name for ``output``) with ``quality`` (N,) as
    its per-vertex quality."""
    mesh = ms.current_mesh()
    copy = pymeshlab.Mesh(mesh.vertex_matrix(), mesh.face_matrix(), v_scalar_array=np.asarray(quality, dtype=float))
    scratch = pymeshlab.MeshSet()
    scratch.add_mesh(copy)
    save_mesh(scratch, path, output)


def report_json(report: dict) -> str:
    """``report`` as the text of a JSON file."""
    return json.dumps(report, indent=2, default=_jsonable) + "\n"


def _jsonable(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON serializable")
