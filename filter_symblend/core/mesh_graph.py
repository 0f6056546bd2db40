"""Graphs of a triangle mesh: its vertex adjacency and its edge lengths (across edges too), and one pair per
vertex of a list of vertex pairs. The automatic pairs' surface, growth and connectivity mirror, and the
semilandmark curves, all build on these."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sparse


def triangle_sides(faces: np.ndarray) -> np.ndarray:
    """(3F, 2) the sides of the triangles ``faces`` (F, 3) as vertex pairs, each once per triangle (an edge
    shared by two triangles twice, once each way on a consistently oriented mesh)."""
    return np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])


def vertex_adjacency(faces: np.ndarray, count: int) -> sparse.csr_matrix:
    """Symmetric (count, count) 0/1 matrix of the mesh edges of ``faces`` (F, 3)."""
    edges = triangle_sides(faces)
    edges = np.concatenate([edges, edges[:, ::-1]])
    adjacency = sparse.csr_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(count, count))
    adjacency.data[:] = 1.0  # an edge shared by two triangles was summed twice
    return adjacency


def one_pair_per_vertex(sources: np.ndarray, twins: np.ndarray):
    """The pairs (sources[i], twins[i]) with each vertex in one pair only (a pair found from both ends counts
    once)."""
    low, high = np.minimum(sources, twins), np.maximum(sources, twins)
    _, first = np.unique(np.column_stack([low, high]), axis=0, return_index=True)
    sources, twins = sources[first], twins[first]
    ends, uses = np.unique(np.concatenate([sources, twins[twins != sources]]), return_counts=True)
    single = (uses[np.searchsorted(ends, sources)] == 1) & (uses[np.searchsorted(ends, twins)] == 1)
    return sources[single], twins[single]


def edge_graph(points: np.ndarray, faces: np.ndarray) -> sparse.csr_matrix:
    """Symmetric (N, N) sparse matrix of straight distances along the mesh's edges and across
    its edges: between the two far corners of every pair of triangles that share an edge. The
    across-edge links let paths run diagonally through the triangulation, which halves the
    zig-zag that makes pure edge paths longer than the geodesic and tessellation-dependent."""
    directed = np.concatenate([faces[:, [0, 1, 2]], faces[:, [1, 2, 0]], faces[:, [2, 0, 1]]])
    key = np.sort(directed[:, :2], axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    key, far = key[order], directed[order, 2]
    shared = np.flatnonzero((key[1:] == key[:-1]).all(axis=1))  # consecutive half-edges of one edge
    links = np.concatenate([key, np.column_stack([far[shared], far[shared + 1]])])
    links = np.unique(np.sort(links, axis=1), axis=0)
    links = links[links[:, 0] != links[:, 1]]
    lengths = np.linalg.norm(points[links[:, 0]] - points[links[:, 1]], axis=1)
    n = len(points)
    graph = sparse.coo_matrix((lengths, (links[:, 0], links[:, 1])), shape=(n, n)).tocsr()
    return (graph + graph.T).tocsr()
