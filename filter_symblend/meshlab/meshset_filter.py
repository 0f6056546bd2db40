"""The pymeshlab face of the filter: read the current mesh, its attributes and its selection into one
validated problem (pipeline/problem), solve it, add the warped mesh as one new layer.

The input layer is never modified. The output is built from a copy of the input (so colours, UVs,
textures and selection survive), its coordinates and quality set through MeshLab's own per-vertex
function filters, then copied once more to drop the scratch attributes (pymeshlab cannot delete
attributes; the copy drops custom attributes). The before/after checks run in a second thread beside the
warp and the layer building. On any failure, a check's included, every layer the filter added is deleted
and the input is current again.
"""

from __future__ import annotations

import dataclasses
import hashlib
import inspect
import time
import warnings
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np
import pymeshlab

from ..core.landmark_pairs import LandmarkPairs
from ..core.mesh_quantities import on_surface
from ..core.report import LandmarkAsymmetry, Report
from ..errors import MeshSetError, ParameterError, SymblendWarning
from ..measures.checks import Checks
from ..measures.hausdorff import two_way_distance
from ..measures.surface_asymmetry import input_asymmetry, input_planes, output_asymmetry, pairs_plane
from ..measures.verdict import nothing_to_restore
from ..parameters import keyword_signature, parameters_doc, validate_parameters
from ..pipeline import MissingRegion, build_problem, solve_problem
from . import recording
from .attributes import landmark_attribute_values, landmarks_from_attributes, read_attributes
from .output_layer import (ASYMMETRY_ATTRIBUTE, CONFIDENCE_ATTRIBUTE, TWIN_ATTRIBUTE, UNCERTAINTY_ATTRIBUTE,
                           add_output_layer)

FILTER_NAME = "generate_symmetrized_mesh"
DISPLAY_NAME = "Symmetrize: Closed-form Blending of Local Symmetries"
_ATTRIBUTE_OPTIONS = ("pair_attribute", "midline_attribute", "weight_attribute")  # the attributes the filter reads
WRITTEN = (ASYMMETRY_ATTRIBUTE, TWIN_ATTRIBUTE, CONFIDENCE_ATTRIBUTE, UNCERTAINTY_ATTRIBUTE)


def _missing_region(mesh: pymeshlab.Mesh, faces: np.ndarray, region: str, weight_attribute: str,
                    weights: np.ndarray | None) -> MissingRegion | None:
    """The missing region ``missing_region`` names, or None for 'none'; ``faces`` (F, 3): the mesh's, as
    read; ``weights``: the mesh's ``weight_attribute`` (None: it has none)."""
    if region == "none":
        return None
    if mesh.is_point_cloud():
        raise MeshSetError(f"`missing_region='{region}'` needs faces to mirror, and the current mesh "
                           f"('{mesh.label()}') is a point cloud; use missing_region='none'.")
    if region == "weight":
        if weights is None:
            raise MeshSetError(
                f"`missing_region='weight'` reads the per-vertex attribute `{weight_attribute}`, and the "
                f"current mesh ('{mesh.label()}') has none. Add it (1 intact, 0 missing), or use "
                "missing_region='selection'.")
        return MissingRegion(1.0 - np.clip(weights, 0.0, 1.0))
    selected_faces = mesh.face_selection_array()
    missing = mesh.vertex_selection_array().astype(float)
    unselected_face_at = np.zeros(mesh.vertex_number(), dtype=bool)
    unselected_face_at[faces[~selected_faces].ravel()] = True
    missing[on_surface(faces, mesh.vertex_number()) & ~unselected_face_at] = 1.0
    if not missing.any():
        warnings.warn(f"`missing_region='selection'`, but no vertex of the current mesh ('{mesh.label()}') is "
                      "selected, nor surrounded by selected faces: nothing is filled. (Hole filling selects "
                      "its new faces with ms.meshing_close_holes(newfaceselected=True, refinehole=True).)",
                      SymblendWarning, stacklevel=4)
        return None
    return MissingRegion(missing, selected_faces)


def _fingerprint(mesh: pymeshlab.Mesh, options: dict, found: dict[str, np.ndarray]) -> str:
    """A digest of everything the filter reads from ``mesh`` (its landmark attributes ``found``, read once):
    equal digests, equal results."""
    digest = hashlib.sha1(repr(sorted(options.items())).encode())
    for array in (mesh.vertex_matrix(), mesh.face_matrix(), mesh.vertex_selection_array(),
                  mesh.face_selection_array()):
        digest.update(np.ascontiguousarray(array).tobytes())
    for name in (options[option] for option in _ATTRIBUTE_OPTIONS):
        values = found.get(name)
        digest.update(b"-" if values is None else values.tobytes())
    return digest.hexdigest()


def _mirror_check(side, points: np.ndarray, faces: np.ndarray, starts, diagonal: float, solved) -> dict:
    """Mirror asymmetry of the surface (points (N, 3), faces) by ``side`` (input_asymmetry or
    output_asymmetry: one rule for both) against the ``solved`` pairs' plane on it refined (None: from the
    planes ``starts``, a future of the input's distinct planes), relative to the input's ``diagonal``,
    without per-vertex values."""
    measured = side(points, faces, starts.result(), diagonal, solved=solved)
    return {k: v for k, v in measured.items() if k != "per_vertex"}


def _timed(seconds: dict, name: str, function, *args):
    """``function(*args)``, its duration written to ``seconds[name]`` (a check's own time, in its thread)."""
    start = time.perf_counter()
    value = function(*args)
    seconds[name] = time.perf_counter() - start
    return value


def _solved_plane(points: np.ndarray, landmarks, mirror_pairs):
    """The plane (measures/surface_asymmetry.pairs_plane) on ``points`` (N, 3), the input's or the output's,
    of the pairs solved: every automatic twin of ``mirror_pairs`` the map supports (confidence above 0) when
    there are some, else the checked ``landmarks``' pairs with both sides given (weight > 0); None when they do
    not fix one."""
    if mirror_pairs is not None:
        supported = mirror_pairs.confidence > 0
        return pairs_plane(points[mirror_pairs.vertex[supported]], mirror_pairs.twins_on(points)[supported])
    left, right = landmarks.both_sides()
    return pairs_plane(points[left], points[right])


def _compute(mesh: pymeshlab.Mesh, options: dict, found: dict, given: LandmarkPairs | None, progress,
             pool: ThreadPoolExecutor, seconds: dict):
    """(the warp of ``mesh`` with the fill of its missing region, {"before", "after", "hausdorff": future} of
    its checks); no layer added. ``options``: every parameter, validated; ``found``: the mesh's landmark
    attributes, read once (meshlab/attributes.read_attributes); ``given``: the landmarks a caller already
    holds, used instead of decoding ``found``. The checks run in ``pool`` once the problem is valid, each
    against the solved pairs' plane on its surface (measures/surface_asymmetry): the input's beside the warp
    with landmark pairs, once they are known with automatic pairs; the output's once the warp is known. Each
    check's own seconds go to ``seconds`` under its report key."""
    faces = mesh.face_matrix()
    region = _missing_region(mesh, faces, options["missing_region"], options["weight_attribute"],
                             found.get(options["weight_attribute"]))
    landmarks = given  # with automatic pairs alone, the landmark attributes are only carried
    if options["pairs"] != "auto" and given is None:
        landmarks = landmarks_from_attributes(found, mesh.label(), *(options[name] for name in _ATTRIBUTE_OPTIONS))
    problem = build_problem(mesh.vertex_matrix(), options, landmarks, faces, missing=region)
    points, faces = problem.points, problem.faces
    diagonal = problem.diagonal
    checks = {}

    def check_input(mirror_pairs) -> Future:
        """Submit the input's check, against the plane of the pairs solved; the future of its planes."""
        solved = _solved_plane(points, problem.landmarks, mirror_pairs)
        starts = pool.submit(_timed, seconds, "input_planes", input_planes, points, faces, solved)
        checks["before"] = pool.submit(_timed, seconds, "mirror_asymmetry_before", _mirror_check, input_asymmetry,
                                       points, faces, starts, diagonal, solved)
        return starts

    if options["checks"] != "none" and options["pairs"] == "landmarks":  # the pairs are known: beside the warp
        starts = check_input(None)
    result = solve_problem(problem, progress)
    if options["checks"] != "none":
        if "before" not in checks:  # automatic pairs: known now
            starts = check_input(result.mirror_pairs)
        checks["after"] = pool.submit(
            _timed, seconds, "mirror_asymmetry_after", _mirror_check, output_asymmetry, result.points, faces, starts,
            diagonal, _solved_plane(result.points, problem.landmarks, result.mirror_pairs))
    if options["checks"] == "full":
        checks["hausdorff"] = pool.submit(_timed, seconds, "hausdorff_input_output", two_way_distance, points, faces,
                                          result.points, faces)
    return result, checks


def _needs_nothing(checks: dict[str, Future], landmarks: LandmarkAsymmetry | None) -> bool:
    """Whether the (finished) checks and the landmark pairs' own asymmetry (``landmarks``, None without
    landmark pairs) say there is nothing to restore (measures/verdict.nothing_to_restore)."""
    if "before" not in checks:
        return False
    return nothing_to_restore(checks["before"].result(), checks["after"].result(),
                              None if landmarks is None else landmarks.max_relative)


def _the_input(result, points: np.ndarray, frame: str):
    """``result`` with the input ``points`` (N, 3) as its output (in the canonical ``frame`` if asked) and no
    asymmetry removed."""
    if frame == "canonical":
        transform = result.report.canonical_from_input
        points = points @ transform[:3, :3].T + transform[:3, 3]
    return dataclasses.replace(result, points=np.array(points, dtype=float), asymmetry=np.zeros(len(points)))


@dataclasses.dataclass(frozen=True)
class FilterRun:
    """One call of the filter: its ``report`` and the layers it read (``input_mesh_id``) and added."""

    report: Report
    input_mesh_id: int
    output_mesh_id: int

    def to_dict(self) -> dict:
        """What ``generate_symmetrized_mesh`` returns: the report's JSON form and the two layer ids."""
        return {**self.report.to_dict(), "input_mesh_id": self.input_mesh_id, "output_mesh_id": self.output_mesh_id}


def run_filter(ms: pymeshlab.MeshSet, params: dict, progress=None, cache: dict | None = None,
               landmarks: LandmarkPairs | None = None) -> FilterRun:
    """``generate_symmetrized_mesh`` with an optional result ``cache`` (fingerprint -> result), so a
    script rehearsed on a copy of the MeshSet does not compute the same warp twice. ``landmarks``: pairs
    the caller already holds (the command, from a landmark file), used instead of the mesh's attributes
    and written as those attributes onto the output layer only (unchecked; the problem checks them).

    The before/after checks (numpy and scipy) run in a second thread beside the warp and beside
    MeshLab's filters building the output layer (which release the GIL). The report's ``seconds`` holds the
    core's stages and ``total`` (the core), ``checks`` (each check's own seconds: ``input_planes``, then
    each figure's measurement after it; they overlap the core) and ``filter`` (the whole call)."""
    clock = time.perf_counter()
    options = validate_parameters(params)
    if ms.mesh_number() == 0:
        raise MeshSetError(
            "The MeshSet has no current mesh. Load one first, e.g. ms.load_new_mesh('skull.ply')."
        )
    input_id = ms.current_mesh_id()
    mesh = ms.current_mesh()
    names = [options[name] for name in _ATTRIBUTE_OPTIONS]
    if len(set(names)) < len(names) or set(WRITTEN) & set(names):
        raise ParameterError(
            f"`pair_attribute`, `midline_attribute` and `weight_attribute` must be three different "
            f"names, none of them {', '.join(f'`{name}`' for name in WRITTEN)} (the filter writes them); "
            f"got {', '.join(names)}.")
    if landmarks is None:  # read once: the landmarks, the missing region, the output layer
        carried = read_attributes(mesh, names)
    else:
        carried = landmark_attribute_values(mesh.vertex_number(), landmarks, tuple(names),
                                            *((landmarks.left_weights, landmarks.right_weights)
                                              if landmarks.is_weighted() else ()))
    key = None if cache is None else _fingerprint(mesh, options, carried)
    result = None if cache is None else cache.get(key)
    if result is not None:
        with recording.recorded_call(ms, options):  # our native steps, saved as one node of ours
            output_id = add_output_layer(ms, input_id, result, carried)
    else:
        check_seconds = {}
        with ThreadPoolExecutor(max_workers=1) as pool:
            result, checks = _compute(mesh, options, carried, landmarks, progress, pool, check_seconds)
            with recording.recorded_call(ms, options):
                output_id = add_output_layer(ms, input_id, result, carried, list(checks.values()))
                unchanged = _needs_nothing(checks, result.report.landmark_asymmetry_before)
                if unchanged:  # rare: the layer is built again from the input rather than wait for the checks
                    result = _the_input(result, ms.mesh(input_id).vertex_matrix(), options["output_frame"])
                    ms.set_current_mesh(output_id)
                    ms.delete_current_mesh()
                    output_id = add_output_layer(ms, input_id, result, carried)
        report = result.report
        report = report.replace(seconds=dataclasses.replace(report.seconds, checks=check_seconds))
        if "after" in checks:
            report = report.replace(checks=Checks.measured({name: check.result() for name, check in checks.items()},
                                                           report, options["pairs"] != "landmarks", unchanged))
        result = dataclasses.replace(result, report=report)
        if cache is not None:
            cache[key] = result
    report = result.report
    report = report.replace(seconds=dataclasses.replace(report.seconds, filter=time.perf_counter() - clock))
    return FilterRun(report, input_id, output_id)


def generate_symmetrized_mesh(ms: pymeshlab.MeshSet, progress=None, **params) -> dict:
    return run_filter(ms, params, progress).to_dict()


_PROGRESS = inspect.Parameter("progress", inspect.Parameter.KEYWORD_ONLY, default=None)
generate_symmetrized_mesh.__signature__ = keyword_signature(
    inspect.Parameter("ms", inspect.Parameter.POSITIONAL_ONLY), _PROGRESS)
generate_symmetrized_mesh.__doc__ = f"""{DISPLAY_NAME}.

Symmetrizes the current mesh from the landmark pairs in its per-vertex scalar
attribute (Ghosh, Amenta, Kazhdan, SGP 2010) and adds the warped mesh as a new
layer, which becomes current. Same vertices (count and order), faces, colours,
UVs and textures as the input; per-vertex quality and the custom attribute
``{ASYMMETRY_ATTRIBUTE}`` hold how far each vertex moved (local asymmetry, in
mesh units, input frame); the pair, midline and weight attributes are
carried over. The input layer
is never modified; on error the MeshSet is left exactly as it was.

Parameters
----------
{parameters_doc()}
progress : callable(percent: float, message: str), optional
    Called at each stage (not a filter parameter: it is not saved in scripts).

Returns
-------
dict
    The report of :func:`filter_symblend.symmetrize` plus ``input_mesh_id`` and
    ``output_mesh_id``.
"""


def _meshset_method(self, progress=None, **params):
    return generate_symmetrized_mesh(self, progress, **params)


_meshset_method.__name__ = FILTER_NAME
_meshset_method.__qualname__ = f"MeshSet.{FILTER_NAME}"
_meshset_method.__doc__ = generate_symmetrized_mesh.__doc__
_meshset_method.__signature__ = keyword_signature(
    inspect.Parameter("self", inspect.Parameter.POSITIONAL_ONLY), _PROGRESS)


def bind_to_meshset() -> None:
    """Add ``MeshSet.generate_symmetrized_mesh`` (pymeshlab binds its own filters the same way)."""
    setattr(pymeshlab.MeshSet, FILTER_NAME, _meshset_method)
