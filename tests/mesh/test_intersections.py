"""Self-intersection detector: exact pairs on hand-built cases, nothing on clean meshes, shared-data counts."""

import numpy as np
import pymeshlab
import pytest
import trimesh

from conftest import icosphere, shared_library
from posefix.mesh.intersections import (intersecting_faces, self_intersecting_pairs, triangle_pairs_intersect,
                                        triangles_intersect_exact)
from posefix.mesh.primitives import capsule
from posefix.io.meshes import read_mesh


def _pairs(V, F):
    return [tuple(p) for p in self_intersecting_pairs(np.asarray(V, float), np.asarray(F)).tolist()]


def _reference_pairs(V, F):
    """Independent float Moller-Trumbore check of every vertex-disjoint pair (general position only)."""
    T = V[F]
    m = len(F)
    out = []
    for f in range(m):
        g = np.arange(f + 1, m)
        g = g[~np.any(F[g][:, :, None] == F[f][None, None, :], axis=(1, 2))]
        hit = np.zeros(len(g), dtype=bool)
        for a, b in ((0, 1), (1, 2), (2, 0)):
            hit |= _segment_hits(T[f, a], T[f, b], T[g])
            hit |= _segments_hit_triangle(T[g, a], T[g, b], T[f])
        out += [(f, int(x)) for x in g[hit]]
    return out


def _segment_hits(p, q, tris):
    return _segments_hit_triangle(np.broadcast_to(p, (len(tris), 3)), np.broadcast_to(q, (len(tris), 3)), tris)


def _segments_hit_triangle(p, q, tri):
    tri = np.broadcast_to(tri, (len(p), 3, 3))
    e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    d = q - p
    h = np.cross(d, e2)
    a = np.einsum("ij,ij->i", e1, h)
    ok = np.abs(a) > 1e-14
    f = 1.0 / np.where(ok, a, 1.0)
    s = p - tri[:, 0]
    u = f * np.einsum("ij,ij->i", s, h)
    qv = np.cross(s, e1)
    v = f * np.einsum("ij,ij->i", d, qv)
    t = f * np.einsum("ij,ij->i", e2, qv)
    return ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0) & (t <= 1)


def test_two_crossing_triangles():
    V = [[0, 0, 0], [2, 0, 0], [0, 2, 0], [0.5, 0.5, -1], [0.5, 0.5, 1], [3, 3, 0]]
    assert _pairs(V, [[0, 1, 2], [3, 4, 5]]) == [(0, 1)]


def test_separated_and_touching_triangles():
    base = [[0, 0, 0], [2, 0, 0], [0, 2, 0]]
    above = base + [[0.5, 0.5, 1e-12], [0.5, 0.5, 1], [3, 3, 1]]
    touching = base + [[0.5, 0.5, 0.0], [0.5, 0.5, 1], [3, 3, 1]]
    assert _pairs(above, [[0, 1, 2], [3, 4, 5]]) == []
    assert _pairs(touching, [[0, 1, 2], [3, 4, 5]]) == [(0, 1)]


def test_coplanar_triangles():
    base = [[0, 0, 0], [2, 0, 0], [0, 2, 0]]
    overlapping = base + [[0.5, 0.5, 0], [3, 0.5, 0], [0.5, 3, 0]]
    disjoint = base + [[1.5, 1.5, 0], [3, 1.5, 0], [1.5, 3, 0]]
    edge_touch = base + [[1, 1, 0], [3, 1, 0], [1, 3, 0]]  # vertex on the hypotenuse x + y = 2
    assert _pairs(overlapping, [[0, 1, 2], [3, 4, 5]]) == [(0, 1)]
    assert _pairs(disjoint, [[0, 1, 2], [3, 4, 5]]) == []
    assert _pairs(edge_touch, [[0, 1, 2], [3, 4, 5]]) == [(0, 1)]


def test_pairs_sharing_a_vertex_are_not_reported():
    # the second triangle passes through the first but shares vertex 0 with it
    V = [[0, 0, 0], [2, 0, 0], [0, 2, 0], [1, 1, -1], [1, 1, 1]]
    assert _pairs(V, [[0, 1, 2], [0, 3, 4]]) == []


def test_folded_strip_known_pairs():
    # a strip s = 0..6 (columns of two triangles) folded back at s = 3..4; its column s = 4..5 crosses
    # the plane z = 0 at x = 1.25, inside the first part's column x = 1..2 (faces 2, 3)
    s = np.arange(7.0)
    x = np.where(s <= 3, s, 6 - s)
    z = np.where(s <= 3, 0.0, -0.5 * (s - 4.75))
    V = np.concatenate([np.stack([x, np.zeros(7), z], 1), np.stack([x, np.ones(7), z], 1)])
    F = [f for c in range(6) for f in ([c, c + 1, 7 + c + 1], [c, 7 + c + 1, 7 + c])]
    assert _pairs(V, F) == [(2, 8), (3, 8), (3, 9)]


def test_interpenetrating_spheres_match_independent_checks():
    V1, F1 = icosphere(2)
    V2, F2 = icosphere(2, centre=(1.2, 0.13, 0.07))
    V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
    pairs = _pairs(V, F)
    assert pairs == _reference_pairs(V, F)
    assert len(pairs) > 20 and all(f < len(F1) <= g for f, g in pairs)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(V, F))
    ms.compute_selection_by_self_intersections_per_face()
    selected = np.flatnonzero(ms.current_mesh().face_selection_array())
    assert np.array_equal(selected, np.flatnonzero(intersecting_faces(np.array(pairs), len(F))))


def _brute_force_pairs(V, F):
    """Every vertex-disjoint face pair decided by the exact integer test alone, sorted."""
    return [(f, g) for f in range(len(F)) for g in range(f + 1, len(F))
            if not set(F[f]) & set(F[g]) and triangles_intersect_exact(V[F[f]], V[F[g]])]


@pytest.mark.parametrize("seed", range(4))
def test_crumpled_meshes_equal_brute_force(seed):
    # a sphere with its vertices snapped to a coarse integer grid and shuffled in place: many crossings,
    # coplanar and touching pairs, repeated and collinear vertices, zero-area faces
    rng = np.random.default_rng(seed)
    V, F = icosphere(1)
    V = np.round(V * 3) + rng.integers(-1, 2, size=V.shape) * (1 + seed % 2)
    if seed >= 2:
        V[rng.choice(len(V), 6, replace=False)] = V[rng.choice(len(V), 6, replace=False)]
    pairs = _pairs(V, F)
    assert pairs == _brute_force_pairs(V, F)
    assert len(pairs) > 10


@pytest.mark.parametrize("mesh", ["icosphere", "capsule", "torus", "demo"])
def test_clean_meshes_have_no_intersections(mesh, demo):
    if mesh == "icosphere":
        V, F = icosphere(4)
    elif mesh == "capsule":
        V, F = capsule()
    elif mesh == "torus":
        t = trimesh.creation.torus(major_radius=1.0, minor_radius=0.3, major_sections=64, minor_sections=24)
        V, F = np.asarray(t.vertices), np.asarray(t.faces)
    else:
        V, F = demo[0], demo[1]
    assert len(self_intersecting_pairs(V, F)) == 0


def test_vectorized_and_rational_tests_agree_on_coplanar_and_degenerate_pairs():
    rng = np.random.default_rng(5)
    A = rng.integers(-4, 5, size=(300, 3, 3)).astype(float)
    B = rng.integers(-4, 5, size=(300, 3, 3)).astype(float)
    A[:150, :, 2] = 0.0  # coplanar half
    B[:150, :, 2] = 0.0
    B[150:200, 2] = B[150:200, 0] + 0.5 * (B[150:200, 1] - B[150:200, 0])  # zero-area triangles
    fast = triangle_pairs_intersect(A, B)
    exact = np.array([triangles_intersect_exact(a, b) for a, b in zip(A, B)])
    assert np.array_equal(fast, exact)
    assert np.array_equal(fast[:150], [_coplanar_reference(a[:, :2], b[:, :2]) for a, b in zip(A[:150], B[:150])])


def _coplanar_reference(a, b):
    """Separating-axis test of two closed 2D triangles (exact for small integer coordinates)."""
    for tri in (a, b):
        for i in range(3):
            e = tri[(i + 1) % 3] - tri[i]
            axis = np.array([-e[1], e[0]])
            if not axis.any():
                continue
            pa, pb = a @ axis, b @ axis
            if pa.max() < pb.min() or pb.max() < pa.min():
                return False
    for tri in (a, b):  # degenerate triangles: also test the segment directions' normals
        for i in range(3):
            e = tri[(i + 1) % 3] - tri[i]
            if e.any():
                pa, pb = a @ e, b @ e
                if pa.max() < pb.min() or pb.max() < pa.min():
                    return False
    return True


def test_lion_counts_match_the_independent_check_of_sources_md():
    folder = shared_library("lion-poses")
    expected = {"lion-01": 465, "lion-02": 201, "lion-03": 166, "lion-04": 717, "lion-05": 132,
                "lion-06": 140, "lion-07": 903, "lion-08": 320, "lion-09": 347, "lion-reference": 138}
    for name, count in expected.items():
        V, F = read_mesh(folder / f"{name}.obj")
        assert intersecting_faces(self_intersecting_pairs(V, F), len(F)).sum() == count, name
