"""Harmonic and biharmonic extension on a mesh graph: exact on linear data of a regular grid, zero without data,
smooth bumps from point data."""

import numpy as np

from conftest import grid_sheet as _grid
from posefix.mesh.harmonic import biharmonic_extension, harmonic_extension
from posefix.mesh.topology import grow_rings, vertex_adjacency


def test_linear_function_is_reproduced_inside_a_regular_grid():
    # every interior vertex of this triangulation has neighbours symmetric about it,
    # so a linear function is discrete-harmonic for the uniform Laplacian
    V, F = _grid(9, 0.0)
    A = vertex_adjacency(F, len(V))
    values = np.column_stack([2 * V[:, 0] - V[:, 1] + 0.5, V[:, 1]])
    boundary = (V[:, :2] == 0).any(axis=1) | (V[:, :2] == 1).any(axis=1)
    out = harmonic_extension(A, np.where(boundary[:, None], values, 99.0), boundary)
    assert np.allclose(out, values, atol=1e-12)


def test_unanchored_components_get_zero_and_known_values_are_kept():
    V1, F1 = _grid(5, 0.0)
    F = np.vstack([F1, F1 + len(V1)])  # two separate sheets
    A = vertex_adjacency(F, 2 * len(V1))
    known = np.zeros(2 * len(V1), dtype=bool)
    known[:3] = True
    values = np.ones((2 * len(V1), 3))
    out = harmonic_extension(A, values, known)
    assert np.allclose(out[:len(V1)], 1.0)  # constant data: constant extension
    assert not out[len(V1):].any()  # the second sheet touches no known vertex


def test_biharmonic_bump_from_one_vertex_is_smooth_and_local():
    """One known vertex in a 4-ring support: zero outside, the value at the vertex, between 0 and it inside,
    flatter at the top than the harmonic cone (neighbours closer to the peak)."""
    V, F = _grid(21, 0.0)
    A = vertex_adjacency(F, len(V))
    centre = np.zeros(len(V), dtype=bool)
    centre[10 * 21 + 10] = True
    support = grow_rings(centre, A, 4) & ~centre
    values = np.where(centre[:, None], [1.0, -2.0], 0.0)
    out = biharmonic_extension(A, values, centre, support)
    assert np.array_equal(out[centre], values[centre]) and not out[~(support | centre)].any()
    assert (out[support, 0] > 0).all() and (out[support, 0] < 1).all() and np.allclose(out[:, 1], -2 * out[:, 0])
    cone = harmonic_extension(A, values, ~support)
    ring1 = (A @ centre) & support
    assert (out[ring1, 0] > cone[ring1, 0]).all()
