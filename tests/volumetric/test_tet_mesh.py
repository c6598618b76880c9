"""The coarse tet mesh of a surface: deterministic, positive, connected, filling the surface's volume."""

import numpy as np
import pytest

from posefix.mesh.primitives import capsule
from posefix.volumetric.operators import tet_adjacency, tet_volumes
from posefix.volumetric.tet_mesh import tet_mesh


def enclosed_volume(V, F):
    """Volume inside a closed, outward-oriented triangle mesh (divergence theorem)."""
    return np.einsum("ij,ij->i", V[F[:, 0]], np.cross(V[F[:, 1]], V[F[:, 2]])).sum() / 6.0


@pytest.fixture(scope="module")
def limb():
    V, F = capsule(around=24, length_rings=30)
    return V, F, tet_mesh(V, F, surface_vertices=300)


def test_the_tet_mesh_is_deterministic_positive_and_connected(limb):
    V, F, (X, T) = limb
    X2, T2 = tet_mesh(V, F, surface_vertices=300)
    assert np.array_equal(X, X2) and np.array_equal(T, T2)
    assert np.all(tet_volumes(X, T) > 0) and len(np.unique(T)) == len(X)
    from scipy.sparse.csgraph import connected_components
    assert connected_components(tet_adjacency(T), directed=False)[0] == 1


def test_the_tets_fill_the_surface_s_volume(limb):
    V, F, (X, T) = limb
    assert tet_volumes(X, T).sum() == pytest.approx(enclosed_volume(V, F), rel=0.05)
    assert 250 <= np.sum(np.isin(np.arange(len(X)), T)) and len(X) < 2 * 300 + 400


def test_the_lion_reference_with_its_self_intersections_gets_the_same_tets_twice():
    from conftest import shared_library
    from posefix.io.meshes import read_mesh
    V, F = read_mesh(shared_library("lion-poses") / "lion-reference.obj")
    X, T = tet_mesh(V, F)
    X2, T2 = tet_mesh(V, F)
    assert np.array_equal(X, X2) and np.array_equal(T, T2) and np.all(tet_volumes(X, T) > 0)
    assert 15000 < len(T) < 30000
