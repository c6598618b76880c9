"""Connectivity: adjacency, edges, face pairs, rings and components on hand-built meshes."""

import numpy as np

from conftest import grid_sheet, icosphere
from posefix.mesh.topology import (edges, face_adjacency, grow_rings, half_edges, selection_components,
                                   vertex_adjacency, vertex_components)

QUAD_F = np.array([[0, 1, 2], [0, 2, 3]])  # two triangles sharing the edge 0-2


def test_adjacency_and_edges_of_a_quad():
    A = vertex_adjacency(QUAD_F, 4)
    assert A.toarray().astype(int).tolist() == [[0, 1, 1, 1], [1, 0, 1, 0], [1, 1, 0, 1], [1, 0, 1, 0]]
    assert edges(QUAD_F).tolist() == [[0, 1], [0, 2], [0, 3], [1, 2], [2, 3]]
    assert half_edges(QUAD_F)[:3].tolist() == [[0, 1], [1, 2], [0, 2]]
    assert face_adjacency(QUAD_F).tolist() == [[0, 1]]


def test_closed_surface_euler_characteristic():
    V, F = icosphere(2)
    assert len(V) - len(edges(F)) + len(F) == 2
    assert len(face_adjacency(F)) == len(edges(F))  # every edge has two faces


def test_rings_on_a_grid():
    V, F = grid_sheet(5, 0.0)
    A = vertex_adjacency(F, len(V))
    seed = np.zeros(len(V), dtype=bool)
    seed[12] = True  # the middle vertex
    assert grow_rings(seed, A, 0).sum() == 1 and grow_rings(seed, A, 1).sum() == 7  # six neighbours
    assert grow_rings(seed, A, 2).sum() < len(V) and grow_rings(seed, A, 4).all()


def test_components_with_and_without_links():
    F = np.vstack([QUAD_F, QUAD_F + 4])  # two separate quads
    labels, count = vertex_components(F, 9)  # vertex 8 is isolated
    assert count == 3 and labels[0] == labels[3] != labels[4] and labels[8] not in labels[:8]
    A = vertex_adjacency(F, 9)
    picked = np.ones(9, dtype=bool)
    picked[2] = False  # 0 and 1, 3 still connect through 0
    parts = selection_components(picked, A)
    assert [p.tolist() for p in parts] == [[0, 1, 3], [4, 5, 6, 7], [8]]
    linked = selection_components(picked, A, np.array([[1, 5], [2, 8]]))  # 2 is not selected: ignored
    assert [p.tolist() for p in linked] == [[0, 1, 3, 4, 5, 6, 7], [8]]
    assert selection_components(np.zeros(9, dtype=bool), A) == []
