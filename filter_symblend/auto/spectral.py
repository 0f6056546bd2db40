"""The shape's intrinsic mirror symmetry, from the Laplace-Beltrami operator of its surface.

Bending a shape and swinging its limbs barely change distances measured along the surface, and so
barely change the eigenfunctions of its Laplace-Beltrami operator. A mirror symmetry maps the
surface onto itself preserving those distances, so each eigenfunction (of a simple eigenvalue) is
even or odd under it, and in the eigenbasis the mirror is the functional map diagonal with +1 and
-1 (Ovsjanikov, Sun and Guibas, *Global intrinsic symmetries of shapes*, SGP 2008). Which sign goes
with which function is found in closed form, without any guess of the mirror, by one linear least
squares problem (Ren, Poulenard, Wonka and Ovsjanikov, *Continuous and orientation-preserving
correspondences via functional maps*, SIGGRAPH Asia 2018):

- the mirror keeps functions the shape defines intrinsically (heat kernel signatures at several
  scales, which are even), ``C A = A``;
- it commutes with the operator, ``C Lambda = Lambda C`` (block diagonal where eigenvalues repeat);
- it reverses the surface's orientation: for an even function f, the operator
  g -> <n, grad f x grad g> anticommutes with it, ``C O_f = -O_f C``. This is what tells the mirror
  from the identity, which satisfies the other two.

The map is then refined to a point map by ZoomOut (Melzi et al., SIGGRAPH Asia 2019): point map ->
functional map on k functions -> point map, with k growing, each functional map projected onto the
symmetric orthogonal matrices (a mirror applied twice is the identity). Its steps map a farthest-point sample
of the vertices only, each carrying the mass of the vertices nearest it, and the last functional map gives
every vertex its twin (as Magnet and Ovsjanikov, *Scalable and efficient functional map computations on dense
meshes*, Eurographics 2023, do).

A compression changes surface distances, and a strong bend of a thick shape stretches one flank and
shrinks the other; the result is then a rough map, refined extrinsically afterwards
(:mod:`.field`). Large meshes are first coarsened by vertex clustering (:func:`working_mesh`): the
low eigenfunctions do not need every vertex.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sparse
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import ArpackNoConvergence, eigsh
from scipy.spatial import cKDTree

from ..core.geometry import voxel_grid
from ..core.mesh_graph import triangle_sides, vertex_adjacency
from ..core.mesh_quantities import farthest_point_order
from ..core.parallel import in_threads
from .config import AutoConfig

# Heat kernel signatures, at times spread over the spectrum, that the mirror must keep and that enter its
# orientation term: each is a different even function of the shape.
DESCRIPTOR_SCALES = 8
# Weight of the functional map's commutation with the Laplacian, relative to the descriptor and orientation
# terms (each scaled to the descriptors' size): equal footing.
COMMUTATIVITY_WEIGHT = 1.0

# Vertices a ZoomOut step maps (farthest-point sampled): each step's exhaustive search costs samples x n, not
# n x n; a mesh with fewer vertices maps them all.
ZOOMOUT_SAMPLES = 1500
# Rows of point_map's distance block: 128 x n float32, 2.5 MB at n = 5,000, near the cache; 512 rows (10 MB) made
# the same products 1.1-1.7x slower (the ten candidates of a posed 5k body 2.5 -> 2.0 s), the same twins.
POINT_MAP_ROWS = 128
MINIMUM_TRIANGLES = 48  # a working mesh with fewer cannot carry a dozen eigenfunctions (four triangles each)
# First functional map sizes (eigenfunctions) tried: the sign solve is sensitive to the size where the pose is
# strong (a size may give another near-symmetry, or fold a limb onto itself), so each gives a candidate.
STARTS = (8, 12, 16, 20, 24)
# Symmetric shapes, posed or not, measured 0.011-0.055 (FAUST humans, homer); shapes with no mirror symmetry
# 0.12-0.22 (the Stanford bunny, fandisk): the bound lies between, at their geometric middle (docs/benchmarks.md).
DESCRIPTOR_AGREEMENT = 0.08
LANCZOS_SEED = 0  # seed of the Lanczos start vector (eigenbasis): any fixed one makes runs reproducible
# Twins of two neighbouring vertices farther apart than this (x the mesh's median edge length) tear a vertex map:
# ZoomOut's twins are right to a vertex or two, so a continuous map keeps neighbours' twins within about three
# edges, while a limb mapped onto itself beside a body mapped across tears by the limb's width at the joint.
TEAR = 4.0
# The best candidates are each refitted once (REFITTED of them): a functional map on the REFIT_START lowest
# eigenfunctions fitted on the candidate's continuous part only, then ZoomOut to its size. The low eigenfunctions
# vary over whole limbs, so the part that is mapped right decides where a limb mapped onto itself belongs.
REFITTED = 3
REFIT_START = 12


@dataclasses.dataclass(frozen=True)
class WorkingMesh:
    """A connected triangle mesh for the spectral map: ``points`` (n, 3), ``faces`` (f, 3), and
    ``vertex_of`` (N,): the vertex of it that each input vertex is clustered into (-1: none)."""

    points: np.ndarray
    faces: np.ndarray
    vertex_of: np.ndarray


def working_mesh(points: np.ndarray, faces: np.ndarray, usable: np.ndarray, config: AutoConfig) -> WorkingMesh | None:
    """The largest connected piece (by area) of the triangles among ``usable`` (N,) bool vertices, coarsened
    by vertex clustering on a voxel grid to about ``config.spectral_vertices`` vertices if larger; None if no
    piece has enough triangles for a spectrum."""
    keep = usable[faces].all(axis=1)
    faces = faces[keep]
    if not len(faces):
        return None
    index = np.flatnonzero(usable)
    cluster = np.full(len(points), -1)
    if len(index) > config.spectral_vertices:
        keys = voxel_grid(points[index], config.spectral_vertices, steps=16)
        _, cluster[index] = np.unique(keys, return_inverse=True)
    else:
        cluster[index] = np.arange(len(index))
    count = int(cluster.max()) + 1
    coarse = cluster[faces]
    coarse = coarse[(coarse[:, 0] != coarse[:, 1]) & (coarse[:, 1] != coarse[:, 2]) & (coarse[:, 0] != coarse[:, 2])]
    if not len(coarse):
        return None
    coarse = coarse[np.unique(np.sort(coarse, axis=1), axis=0, return_index=True)[1]]
    centres = np.zeros((count, 3))
    np.add.at(centres, cluster[index], points[index])
    centres /= np.maximum(np.bincount(cluster[index], minlength=count), 1)[:, None]
    corners = centres[coarse]
    area = np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    coarse, area = coarse[area > 0], area[area > 0]
    _, piece = connected_components(vertex_adjacency(coarse, count), directed=False)
    largest = np.argmax(np.bincount(piece[coarse[:, 0]], weights=area))
    coarse = coarse[piece[coarse[:, 0]] == largest]
    if len(coarse) < MINIMUM_TRIANGLES:
        return None
    used = np.unique(coarse)
    renumber = np.full(count + 1, -1)  # the last entry: vertices in no cluster (-1) stay -1
    renumber[used] = np.arange(len(used))
    return WorkingMesh(centres[used], renumber[coarse], renumber[cluster])


def cotangent_laplacian(points: np.ndarray, faces: np.ndarray) -> tuple[sparse.csr_matrix, np.ndarray]:
    """The cotangent stiffness matrix (n, n) (positive semidefinite) and the lumped mass (n,) (a third of
    the area of the triangles around each vertex) of the triangles ``faces`` (f, 3) with an area."""
    corners = points[faces]
    doubled = np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    rows, columns, weights = [], [], []
    for k in range(3):
        i, j = faces[:, (k + 1) % 3], faces[:, (k + 2) % 3]
        u, v = corners[:, (k + 1) % 3] - corners[:, k], corners[:, (k + 2) % 3] - corners[:, k]
        half_cotangent = 0.5 * np.einsum("ij,ij->i", u, v) / doubled
        rows += [i, j]
        columns += [j, i]
        weights += [half_cotangent, half_cotangent]
    n = len(points)
    off = sparse.csr_matrix((np.concatenate(weights), (np.concatenate(rows), np.concatenate(columns))), shape=(n, n))
    stiffness = sparse.diags(np.asarray(off.sum(axis=1)).ravel()) - off
    mass = np.bincount(faces.ravel(), np.repeat(doubled / 6.0, 3), minlength=n)
    return stiffness.tocsr(), mass


@dataclasses.dataclass(frozen=True)
class Eigenbasis:
    """The lowest eigenpairs of the Laplace-Beltrami operator: ``values`` (k,) ascending, ``functions``
    (n, k) orthonormal in the ``mass`` (n,) inner product."""

    values: np.ndarray
    functions: np.ndarray
    mass: np.ndarray


def eigenbasis(points: np.ndarray, faces: np.ndarray, count: int) -> Eigenbasis | None:
    """The ``count`` lowest eigenpairs (shift-invert Lanczos, scipy's ``eigsh``), or None if they do not
    converge. The Lanczos start is seeded (ARPACK's own is random), so that near-repeated eigenvalues, and
    every map built on them, come out the same on every run."""
    stiffness, mass = cotangent_laplacian(points, faces)
    mass = np.maximum(mass, 1e-12 * mass.max())
    count = min(count, len(points) - 2)
    shift = -1e-8 * float(np.abs(stiffness.diagonal()).mean() / mass.mean())
    try:
        values, functions = eigsh(stiffness, k=count, M=sparse.diags(mass), sigma=shift, which="LM",
                                  v0=np.random.default_rng(LANCZOS_SEED).standard_normal(len(points)))
    except (ArpackNoConvergence, RuntimeError):
        return None
    order = np.argsort(values)
    return Eigenbasis(values[order], functions[:, order], mass)


def heat_kernel_signatures(basis: Eigenbasis, scales: int) -> np.ndarray:
    """(n, scales) heat kernel signatures (Sun, Ovsjanikov and Guibas 2009) at times spread between the
    heat's decay over the highest and the lowest non-zero eigenvalue, each normalized to unit mass norm."""
    times = np.geomspace(4.0 * np.log(10.0) / basis.values[-1], 4.0 * np.log(10.0) / basis.values[1], scales)
    signatures = (basis.functions ** 2) @ np.exp(-np.outer(basis.values, times))
    return signatures / np.sqrt((basis.mass[:, None] * signatures ** 2).sum(axis=0))


def orientation_operators(points: np.ndarray, faces: np.ndarray, functions: np.ndarray,
                          descriptors: np.ndarray) -> np.ndarray:
    """(d, k, k): for each descriptor f (column of ``descriptors`` (n, d)), the matrix of
    g -> <n, grad f x grad g> in the basis ``functions`` (n, k): entry (i, j) is the integral of
    phi_i <n, grad f x grad phi_j>, with gradients constant on each triangle."""
    corners = points[faces]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    doubled = np.linalg.norm(normal, axis=1)
    normal /= doubled[:, None]
    values = np.column_stack([descriptors, functions])
    gradient = np.zeros((len(faces), 3, values.shape[1]))
    for k in range(3):
        edge = corners[:, (k + 2) % 3] - corners[:, (k + 1) % 3]  # the edge opposite corner k
        gradient += (np.cross(normal, edge) / doubled[:, None])[:, :, None] * values[faces[:, k]][:, None, :]
    d = descriptors.shape[1]
    on_faces = functions[faces].mean(axis=1) * (0.5 * doubled)[:, None]  # phi_i times the triangle's area
    operators = np.empty((d, functions.shape[1], functions.shape[1]))
    for index in range(d):
        crossed = np.cross(gradient[:, :, index][:, :, None], gradient[:, :, d:], axisa=1, axisb=1, axisc=1)
        operators[index] = on_faces.T @ np.einsum("fa,fak->fk", normal, crossed)
    return operators


def closest_symmetric_orthogonal(matrix: np.ndarray) -> np.ndarray:
    """The symmetric orthogonal matrix (an involution) nearest ``matrix`` (k, k)."""
    values, vectors = np.linalg.eigh(0.5 * (matrix + matrix.T))
    return (vectors * np.where(values >= 0, 1.0, -1.0)) @ vectors.T


def mirror_functional_map(basis: Eigenbasis, count: int, descriptors: np.ndarray,
                          operators: np.ndarray) -> np.ndarray:
    """The (count, count) functional map of the orientation-reversing intrinsic symmetry on the first
    ``count`` eigenfunctions (see the module doc), projected onto the involutions; ``descriptors`` (n, d): the
    heat kernel signatures of ``basis`` (:func:`heat_kernel_signatures`, DESCRIPTOR_SCALES of them);
    ``operators`` (d, k, k), k >= count: their :func:`orientation_operators` on the first k eigenfunctions (the
    first ``count`` rows and columns are those on ``count``).

    The least squares in vec(C) (column-major) has rows A^T kron I (C A = A), O^T kron I + I kron O for each
    operator O (C O + O C = 0) and a diagonal (C Lambda = Lambda C); its normal matrix is formed from the
    Kronecker identities (O^T kron I + I kron O)^T (...) = O O^T kron I + O kron O + O^T kron O^T + I kron O^T O,
    never from the (count^2 (d + 2), count^2) design matrix: at count 24 the solve takes 0.02 s where scipy's
    least squares on that matrix took 0.24 s (the same maps on every BCICP shape, docs/benchmarks.md; the
    normal matrix's condition number there at most 2.5e5)."""
    functions = basis.functions[:, :count]
    coefficients = functions.T @ (basis.mass[:, None] * descriptors)  # (count, d), preserved by the mirror
    identity = np.eye(count)
    scale = np.linalg.norm(coefficients)
    kept = coefficients @ coefficients.T
    normal = np.kron(kept, identity)
    for operator in operators[:, :count, :count]:
        operator = operator * (scale / (np.linalg.norm(operator) or 1.0))
        normal += (np.kron(operator @ operator.T, identity) + np.kron(operator, operator)
                   + np.kron(operator.T, operator.T) + np.kron(identity, operator.T @ operator))
    values = basis.values[:count] / basis.values[count - 1]
    gaps = (values[:, None] - values[None, :]) ** 2
    normal[np.diag_indices_from(normal)] += (COMMUTATIVITY_WEIGHT * scale * gaps.reshape(-1, order="F")) ** 2
    solution = np.linalg.solve(normal, kept.reshape(-1, order="F"))
    return closest_symmetric_orthogonal(solution.reshape(count, count, order="F"))


def point_map(functions: np.ndarray, functional: np.ndarray, queries: np.ndarray | None = None) -> np.ndarray:
    """(n,) vertex map of a functional map: each vertex goes to the vertex whose spectral coordinates are
    nearest its own mapped ones (``functions`` (n, k) @ ``functional`` (k, k)); with ``queries`` (q,), the
    twins of those vertices only (q,). Exhaustive, by blocks of POINT_MAP_ROWS rows of |y|^2 - 2 x.y in
    float32: in 12-60 dimensions a k-d tree prunes little (on 5,000 vertices 0.9 s against 0.027 s at 60), and
    ZoomOut calls this about 110 times a run (mostly for its sample). float32 is 3x faster than float64; on
    four BCICP shapes it changed the ZoomOut twin of 0-16 of about 5,000 vertices (near ties) and no figure of
    the benchmark (docs/benchmarks.md)."""
    mapped = ((functions if queries is None else functions[queries]) @ functional).astype(np.float32)
    functions = functions.astype(np.float32)
    squares = np.einsum("ij,ij->i", functions, functions)
    doubled = -2.0 * functions.T  # one product and one sum in place a block: 1.6x the three passes before
    nearest = np.empty(len(mapped), dtype=np.int64)
    for start in range(0, len(mapped), POINT_MAP_ROWS):
        distances = mapped[start:start + POINT_MAP_ROWS] @ doubled
        distances += squares
        nearest[start:start + POINT_MAP_ROWS] = np.argmin(distances, axis=1)
    return nearest


@dataclasses.dataclass(frozen=True)
class SpectralSample:
    """The vertices ZoomOut's steps map, ``vertices`` (s,), each with the mass (s,) of the vertices nearest
    it: the quadrature of the functional map's inner products."""

    vertices: np.ndarray
    mass: np.ndarray

    @classmethod
    def of(cls, points: np.ndarray, mass: np.ndarray, count: int = ZOOMOUT_SAMPLES) -> SpectralSample:
        """``count`` vertices of ``points`` (n, 3) by farthest-point sampling, each with the ``mass`` (n,) of
        the vertices nearest it; every vertex with its own mass when there are no more than ``count``."""
        if len(points) <= count:
            return cls(np.arange(len(points)), mass)
        vertices = np.sort(farthest_point_order(points, count))
        _, nearest = cKDTree(points[vertices]).query(points)
        return cls(vertices, np.bincount(nearest, weights=mass, minlength=count))


def zoomout(basis: Eigenbasis, twins: np.ndarray, start: int, stop: int, step: int,
            sample: SpectralSample) -> np.ndarray:
    """ZoomOut: the map refined on ``start``..``stop`` eigenfunctions, ``step`` at a time, from the ``twins``
    (s,) of the ``sample``'s vertices; the (n,) vertex map of every vertex by the last functional map."""
    counts = list(range(start, stop + 1, step))
    for count in counts:
        functions = basis.functions[:, :count]
        functional = closest_symmetric_orthogonal(
            functions[sample.vertices].T @ (sample.mass[:, None] * functions[twins]))
        if count != counts[-1]:
            twins = point_map(functions, functional, sample.vertices)
    return point_map(functions, functional)


def refit(basis: Eigenbasis, vertex_map: np.ndarray, part: np.ndarray, start: int, step: int,
          sample: SpectralSample) -> np.ndarray:
    """The (n,) vertex map of ZoomOut from ``start`` eigenfunctions to all of ``basis``'s, ``step`` at a time,
    started from the functional map of ``vertex_map`` (n,) fitted on the vertices of ``part`` (n,) bool only."""
    functions = basis.functions[:, :start]
    functional = closest_symmetric_orthogonal(functions.T @ ((basis.mass * part)[:, None] * functions[vertex_map]))
    twins = point_map(functions, functional, sample.vertices)
    return zoomout(basis, twins, start, len(basis.values), step, sample)


def reversed_triangles(points: np.ndarray, faces: np.ndarray, vertex_map: np.ndarray) -> np.ndarray:
    """(f,) bool: whether the vertex map (n,) sends each triangle of ``faces`` (f, 3) of ``points`` (n, 3)
    onto three distinct vertices with its orientation reversed (the image triangle's normal against the
    surface's there), as a mirror does to every triangle; the identity and a rotation do it to none, and a
    map that collapses or scrambles a region fails there."""
    corners = points[faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    vertex_normals = np.zeros_like(points)
    for k in range(3):
        np.add.at(vertex_normals, faces[:, k], normals)
    image = vertex_map[faces]
    distinct = (image[:, 0] != image[:, 1]) & (image[:, 1] != image[:, 2]) & (image[:, 0] != image[:, 2])
    moved = points[image]
    image_normals = np.cross(moved[:, 1] - moved[:, 0], moved[:, 2] - moved[:, 0])
    return distinct & (np.einsum("ij,ij->i", image_normals, vertex_normals[image].sum(axis=1)) < 0)


def reversed_share(points: np.ndarray, faces: np.ndarray, reversed_there: np.ndarray) -> float:
    """The share of the area of the triangles ``faces`` (f, 3) of ``points`` where ``reversed_there`` (f,)
    (:func:`reversed_triangles`): one score for any self-map, how much of the surface it mirrors."""
    corners = points[faces]
    area = np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    return float(area[reversed_there].sum() / area.sum())


def _edges(points: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, float]:
    """(the sides of the triangles ``faces`` (f, 3), (3f, 2): :func:`triangle_sides`; their median length)."""
    edges = triangle_sides(faces)
    return edges, float(np.median(np.linalg.norm(points[edges[:, 0]] - points[edges[:, 1]], axis=1)))


def continuous_part(points: np.ndarray, faces: np.ndarray, vertex_map: np.ndarray, mass: np.ndarray) -> np.ndarray:
    """(n,) bool: the vertices of the largest piece (by ``mass`` (n,)) of the mesh cut along the edges the
    vertex map (n,) tears (:data:`TEAR`), whose twins lie in that piece too."""
    edges, length = _edges(points, faces)
    torn = np.linalg.norm(points[vertex_map[edges[:, 0]]] - points[vertex_map[edges[:, 1]]], axis=1) > TEAR * length
    kept = edges[~torn]
    whole = sparse.coo_matrix((np.ones(len(kept)), (kept[:, 0], kept[:, 1])), shape=(len(points), len(points)))
    _, piece = connected_components(whole, directed=False)
    largest = np.argmax(np.bincount(piece, weights=mass))
    inside = piece == largest
    return inside & inside[vertex_map]


def mirrored_share(points: np.ndarray, faces: np.ndarray, vertex_map: np.ndarray, mass: np.ndarray) -> float:
    """The share of the surface (area of ``faces`` (f, 3)) that the vertex map (n,) mirrors: its triangles
    reversed (:func:`reversed_triangles`) within its continuous part (:func:`continuous_part`). One score for any
    self-map: a map that folds a limb onto itself reverses the limb's triangles too, but tears at the joint."""
    inside = continuous_part(points, faces, vertex_map, mass)
    return reversed_share(points, faces, reversed_triangles(points, faces, vertex_map) & inside[faces].all(axis=1))


def mended_map(points: np.ndarray, faces: np.ndarray, vertex_map: np.ndarray, others: np.ndarray,
               mass: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(``vertex_map`` (n,) with each connected piece of the mesh outside its continuous part
    (:func:`continuous_part`) mapped as the row of ``others`` (m, n) that joins the part there; for each vertex,
    the row its new twin came from (n,), -1 where it kept its own).

    A limb mapped onto itself, beside a body mapped across, tears at the joint; another candidate may send it
    across. The row that joins is the one whose twins of the piece's border vertices land within TEAR edges of
    the twins of their neighbours in the part (the map's own) on more of the border's edges than any other
    row, and on more than half of them: a map is continuous there. Pieces with fewer than three border edges
    are left as they are."""
    n = len(points)
    if not len(others):
        return vertex_map.copy(), np.full(n, -1)
    edges, length = _edges(points, faces)
    part = continuous_part(points, faces, vertex_map, mass)
    outside = ~part
    within = edges[outside[edges[:, 0]] & outside[edges[:, 1]]]
    _, piece = connected_components(sparse.coo_matrix((np.ones(len(within)), (within[:, 0], within[:, 1])),
                                                      shape=(n, n)), directed=False)
    border = edges[outside[edges[:, 0]] & part[edges[:, 1]]]  # (vertex outside, its neighbour in the part)
    owner, pieces = piece[border[:, 0]], piece.max() + 1
    edges_of = np.bincount(owner, minlength=pieces)
    joins = np.array([np.bincount(owner, minlength=pieces, weights=np.linalg.norm(
        points[row[border[:, 0]]] - points[vertex_map[border[:, 1]]], axis=1) <= TEAR * length) for row in others])
    best = np.argmax(joins, axis=0)  # (pieces,)
    taken = (2 * joins[best, np.arange(pieces)] > edges_of) & (edges_of >= 3)
    source = np.where(outside & taken[piece], best[piece], -1)
    mended = vertex_map.copy()
    changed = source >= 0
    mended[changed] = others[source[changed], np.flatnonzero(changed)]
    return mended, source


def descriptor_disagreement(signatures: np.ndarray, vertex_map: np.ndarray) -> float:
    """median |log s(x) - log s(m(x))| / median |log s(x) - log s(y)| over random pairs (x, y): 0 for a map
    that keeps the signatures ``signatures`` (n, d) > 0, about 1 for a random map."""
    logs = np.log(signatures)
    shuffled = np.random.default_rng(0).permutation(len(logs))
    return float(np.median(np.abs(logs - logs[vertex_map])) / np.median(np.abs(logs - logs[shuffled])))


@dataclasses.dataclass(frozen=True)
class CandidateMirror:
    """The intrinsic mirror from a first functional map on ``start`` eigenfunctions, refined by ZoomOut to
    ``size`` eigenfunctions: ``vertex_map`` (n,), its ``descriptor_disagreement``
    (:func:`descriptor_disagreement`) and ``mirrored_share`` (:func:`mirrored_share`); ``refitted_from``: the
    candidate whose continuous part the first functional map was fitted on (:data:`REFIT_START`), if any;
    ``mended_from``: the candidates that map the pieces it tore off (:func:`mended_map`), if any."""

    start: int
    size: int
    vertex_map: np.ndarray
    descriptor_disagreement: float
    mirrored_share: float
    refitted_from: str | None = None
    mended_from: tuple[str, ...] = ()

    @property
    def name(self) -> str:
        """The candidate's name in reports: its first size and its ZoomOut size ("12 -> 100")."""
        name = f"{self.start} -> {self.size}"
        if self.refitted_from is not None:
            name = f"{name} on the continuous part of {self.refitted_from}"
        return name if not self.mended_from else f"{name}, its torn pieces as {' and '.join(self.mended_from)}"

    @property
    def keeps_descriptors(self) -> bool:
        """Whether it keeps the heat kernel signatures as an intrinsic symmetry does (DESCRIPTOR_AGREEMENT)."""
        return self.descriptor_disagreement <= DESCRIPTOR_AGREEMENT


def candidate_mirrors(mesh: WorkingMesh, config: AutoConfig) -> list[CandidateMirror] | None:
    """The intrinsic mirror of ``mesh`` from each first size of STARTS that its spectrum allows, refined by
    ZoomOut to each size of ``config.zoomout_sizes``, the REFITTED best of them refitted on their continuous
    parts, and the best of all with the pieces it tears off mapped by the others (:func:`mended_map`), by
    decreasing mirrored share (:func:`mirrored_share`: the best first); None if the spectrum cannot be computed."""
    basis = eigenbasis(mesh.points, mesh.faces, max(size for size, _ in config.zoomout_sizes))
    if basis is None:
        return None
    signatures = heat_kernel_signatures(basis, DESCRIPTOR_SCALES)
    steps = {min(size, len(basis.values)): step for size, step in config.zoomout_sizes}
    sizes = {size: Eigenbasis(basis.values[:size], basis.functions[:, :size], basis.mass) for size in steps}
    descriptors = {size: heat_kernel_signatures(truncated, DESCRIPTOR_SCALES) for size, truncated in sizes.items()}
    operators = {size: orientation_operators(mesh.points, mesh.faces, truncated.functions[:, :max(STARTS)],
                                             descriptors[size])
                 for size, truncated in sizes.items()}  # once per size: each first map takes its corner
    sample = SpectralSample.of(mesh.points, basis.mass)
    tasks = [(start, size, step) for size, step in steps.items() for start in STARTS if start + 2 <= size]

    def scored(start: int, size: int, vertex_map: np.ndarray, refitted_from: str | None = None,
               mended_from: tuple[str, ...] = ()) -> CandidateMirror:
        return CandidateMirror(start, size, vertex_map, descriptor_disagreement(signatures, vertex_map),
                               mirrored_share(mesh.points, mesh.faces, vertex_map, basis.mass), refitted_from,
                               mended_from)

    def candidate(task: tuple[int, int, int]) -> CandidateMirror:
        start, size, step = task
        truncated = sizes[size]
        functional = mirror_functional_map(truncated, start, descriptors[size], operators[size])
        twins = point_map(truncated.functions[:, :start], functional, sample.vertices)
        return scored(start, size, zoomout(truncated, twins, start, size, step, sample))

    def refitted(mirror: CandidateMirror) -> CandidateMirror:
        start = min(REFIT_START, mirror.size)
        part = continuous_part(mesh.points, mesh.faces, mirror.vertex_map, basis.mass)
        vertex_map = refit(sizes[mirror.size], mirror.vertex_map, part, start, steps[mirror.size], sample)
        return scored(start, mirror.size, vertex_map, mirror.name)

    def mended(mirrors: list[CandidateMirror]) -> list[CandidateMirror]:
        """The best of ``mirrors`` with the pieces it tears off mapped by the others (:func:`mended_map`), if any."""
        best, others = mirrors[0], mirrors[1:]
        vertex_map, source = mended_map(mesh.points, mesh.faces, best.vertex_map,
                                        np.array([mirror.vertex_map for mirror in others]), basis.mass)
        if not (source >= 0).any():
            return []
        return [scored(best.start, best.size, vertex_map, best.refitted_from,
                       tuple(others[index].name for index in np.unique(source[source >= 0])))]

    by_share = lambda mirrors: sorted(mirrors, key=lambda mirror: -mirror.mirrored_share)  # noqa: E731
    found = by_share(in_threads(candidate, tasks))  # one per core: 3.4 -> 2.2 s on a 5k horse, 2 cores
    found = by_share(found + list(in_threads(refitted, found[:REFITTED])))
    return by_share(found + mended(found))
