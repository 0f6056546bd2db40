"""Mesh-graph utilities of the automatic pairs: the vertex adjacency of triangles, and one pair per vertex.

A leaf module: the surface, the growth and the connectivity mirror all use these, and none of them
imports another for them.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sparse


def vertex_adjacency(faces: np.ndarray, count: int) -> sparse.csr_matrix:
    """Symmetric (count, count) 0/1 matrix of the mesh edges of ``faces`` (F, 3)."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
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
