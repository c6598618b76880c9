"""Vertices split along seams: coincident vertices welded for the computation, split again on output.

Game and film assets (and every glTF file) split vertices along UV seams: two or more vertices at one
position, each used by the faces of one side. To the repair they are a cut through the surface: the
sides can drift apart, and the fit sees duplicate constraint points (near-singular). :func:`seam_groups`
finds them in the reference, :class:`Weld` maps a pose to the welded mesh and back; unwelding copies
each welded position to all of its input vertices, so seams stay closed, bit for bit.
"""

from dataclasses import dataclass

import numpy as np
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree
import scipy.sparse as sp

from posefix.mesh.geometry import edge_lengths
from posefix.mesh.topology import edges


def seam_groups(V, F, tol=1e-6):
    """For every vertex the lowest index of the vertices within ``tol`` times the mean edge length of it
    (transitively), (n,) int64: ``group[i] == i`` for a vertex that is not split."""
    radius = tol * float(edge_lengths(V, edges(F)).mean())
    pairs = cKDTree(V).query_pairs(radius, output_type="ndarray")
    n = len(V)
    graph = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n)) if len(pairs) else \
        sp.coo_matrix((n, n))
    _, label = connected_components(graph, directed=False)
    first = np.full(label.max() + 1, n)
    np.minimum.at(first, label, np.arange(n))
    return first[label]


@dataclass(frozen=True)
class Weld:
    """The map between a mesh with split vertices and its welded mesh.

    Attributes
    ----------
    kept : (k,) int64
        Input vertices that stay (the lowest of each group), ascending: ``V_welded = V[kept]``.
    index : (n,) int64
        Welded vertex of every input vertex: ``V_input = V_welded[index]`` (unwelding), ``F_welded = index[F]``.
    """

    kept: np.ndarray
    index: np.ndarray

    @classmethod
    def of(cls, V, F, tol=1e-6):
        """The weld of the reference ``V`` (n, 3), ``F`` (m, 3) (:func:`seam_groups`)."""
        group = seam_groups(V, F, tol)
        kept = np.flatnonzero(group == np.arange(len(V)))
        position = np.empty(len(V), dtype=np.int64)
        position[kept] = np.arange(len(kept))
        return cls(kept, position[group])

    @property
    def split(self):
        """Whether any vertices are welded."""
        return len(self.kept) < len(self.index)

    def faces(self, F):
        """Faces (m, 3) on the welded vertices."""
        return self.index[F]

    def apart(self, X, tol):
        """Input vertices (pairs (p, 2) of indices) welded here but farther apart than ``tol`` in ``X`` (n, 3)."""
        representative = self.kept[self.index]
        gap = np.linalg.norm(X - X[representative], axis=1)
        far = np.flatnonzero(gap > tol)
        return np.column_stack([representative[far], far])

    def weld(self, X):
        """Welded positions (k, 3) of input positions ``X`` (n, 3) (the lowest vertex of each group)."""
        return X[self.kept]

    def unweld(self, X):
        """Input positions (n, 3) of welded positions ``X`` (k, 3): a group's vertices get identical values."""
        return X[self.index]
