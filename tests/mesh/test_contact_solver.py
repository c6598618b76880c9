import ipctk
import numpy as np
import pytest
import scipy.sparse as sp
import trimesh

from conftest import float32_crossing
from posefix.mesh.contact_solver import ContactSettings, ContactSolver
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.mesh.primitives import capsule
from posefix.mesh.rotations import rotation_exp


def sphere(centre, radius=1.0, subdivisions=2):
    s = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return np.asarray(s.vertices) + centre, np.asarray(s.faces)


def union(*parts):
    V, F, offset = [], [], 0
    for Vi, Fi in parts:
        V.append(Vi)
        F.append(Fi + offset)
        offset += len(Vi)
    return np.vstack(V), np.vstack(F)


def test_two_spheres_pushed_into_each_other_stop_with_a_gap_up_to_dhat():
    V, F = union(sphere([-1.2, 0, 0]), sphere([1.2, 0, 0]))
    left = np.arange(len(V)) < len(V) // 2
    goal = V + np.where(left[:, None], [0.6, 0, 0], [-0.6, 0, 0])  # 1 unit of overlap
    solver = ContactSolver(V, F)
    r = solver.compute_pose(V, goal, np.ones(len(V)))
    assert r.converged
    assert 0.0 < r.min_distance <= solver.dhat
    assert len(self_intersecting_pairs(r.X, F)) == 0
    assert r.contact.any() and not r.contact.all()
    # the spheres did move toward each other: only dhat apart at the closest points
    assert r.X[left, 0].max() > -0.01 and r.X[~left, 0].min() < 0.01


def test_a_full_cache_of_inverse_columns_starts_again_with_the_same_steps(monkeypatch):
    """Room for 20 cached columns of Q^-1 (of 324 vertices; 14 to 38 vertices in contact): steps with more vertices
    in contact than fit factorize the whole Hessian, and the pose is the one of an unbounded cache; the cache
    starts again when columns of other vertices no longer fit."""
    import posefix.mesh.contact_solver as contact_solver
    V, F = union(sphere([-1.2, 0, 0]), sphere([1.2, 0, 0]))
    goal = V + np.where((np.arange(len(V)) < len(V) // 2)[:, None], [0.6, 0, 0], [-0.6, 0, 0])
    unbounded = ContactSolver(V, F).compute_pose(V, goal, np.ones(len(V)))
    monkeypatch.setattr(contact_solver, "_SCHUR_BYTES", 20 * 8 * len(V))
    bounded = ContactSolver(V, F).compute_pose(V, goal, np.ones(len(V)))
    assert bounded.converged and bounded.iterations == unbounded.iterations
    assert np.allclose(bounded.X, unbounded.X, rtol=0, atol=1e-9)
    Q = sp.identity(len(V)) + sp.csr_matrix(trimesh.Trimesh(V, F, process=False).edges_sparse, dtype=float) * 0.1
    system = contact_solver._NewtonSystem(Q, [np.arange(len(V))] * 2)
    for vertices in (np.arange(0, 12), np.arange(12, 20), np.arange(100, 110), np.arange(5, 15)):
        columns = system.inverse_columns(vertices)
        assert np.allclose(system.W[columns].T, np.linalg.inv(Q.toarray())[:, vertices], atol=1e-12)
    assert system.count == 20 and len(system.W) == 20  # started again at 100..109, then 5..14 added


def test_a_rigid_motion_of_the_goals_comes_back_exactly():
    V, F = union(sphere([-1.2, 0, 0]), sphere([1.2, 0, 0]))
    R = rotation_exp(np.array([[0.2, -0.5, 0.3]]))[0]
    goal = V @ R.T + [0.3, -2.0, 1.0]
    r = ContactSolver(V, F).compute_pose(V, goal, np.ones(len(V)))
    assert r.converged and not r.contact.any()
    assert np.abs(r.X - goal).max() < 1e-12


def test_a_shape_for_the_smoothness_term_follows_the_goals_above_the_smoothing_length_and_the_shape_below_it():
    V, F = sphere([0, 0, 0], subdivisions=3)
    bumps = 0.02 * np.sin(25 * V[:, [0]]) * V  # fine detail of the goals: a wavelength of 0.25, below l = 0.35
    goal, shape = 1.5 * V + bumps, V + [0.0, 0.0, 0.5]
    solver = ContactSolver(V, F, settings=ContactSettings(smoothing=0.1))
    r = solver.compute_pose(V, goal, np.ones(len(V)), shape=shape)
    assert r.converged and not r.contact.any()
    mass, smooth = solver._smoothness  # the minimum of 1/2 |x - goal|_W^2 + 1/2 |x - shape|_S^2: zero gradient
    assert np.abs(mass[:, None] * (r.X - goal) + smooth @ (r.X - shape)).max() < 1e-9
    radius = np.linalg.norm(r.X - r.X.mean(axis=0), axis=1)
    assert abs(radius.mean() - 1.5) < 0.05  # the goals' scale (their coarsest feature) ...
    assert radius.std() < 0.2 * np.linalg.norm(bumps, axis=1).std()  # ... without their fine bumps
    assert np.abs(solver.compute_pose(V, goal, np.ones(len(V)), shape=goal).X - goal).max() < 1e-12


def test_a_reference_with_its_own_intersections_keeps_them_and_forms_no_new_pair():
    V, F = union(sphere([-0.9, 0, 0]), sphere([0.9, 0, 0]), sphere([0, 2.4, 0], radius=0.8))
    ref_pairs = self_intersecting_pairs(V, F)
    ref_faces = intersecting_faces(ref_pairs, len(F))
    assert 0 < ref_faces.sum() < len(F) // 3
    solver = ContactSolver(V, F, ref_pairs)
    assert solver.compute_pose(V, V, np.ones(len(V))).X.tolist() == V.tolist()  # nothing pushed apart at rest
    n = len(V) // 3
    goal = V.copy()
    goal[n:2 * n] += [-0.5, 0, 0]  # deeper into the first sphere
    goal[2 * n:] += [0, -1.6, 0]  # the third sphere down into the intersecting pair
    r = solver.compute_pose(V, goal, np.ones(len(V)))
    faces = intersecting_faces(self_intersecting_pairs(r.X, F), len(F))
    assert not (faces & ~ref_faces).any()
    assert r.contact.any()
    assert np.abs(r.X[2 * n:, 1] - V[2 * n:, 1]).max() > 0.5  # the third sphere moved until it touched


def test_only_the_primitive_pairs_of_intersecting_face_pairs_are_removed_from_the_candidates():
    box = trimesh.creation.box(extents=[2.0, 2.0, 2.0])
    ball = sphere([0, 0, 0], radius=0.5, subdivisions=3)
    tip = ball[0][np.argmin(ball[0][:, 0])]
    ball = (ball[0] + [0.999 - tip[0], -tip[1], -tip[2]], ball[1])  # its leftmost vertex just through the box face
    V, F = union((np.asarray(box.vertices), np.asarray(box.faces)), ball)
    ref_pairs = self_intersecting_pairs(V, F)
    solver = ContactSolver(V, F, ref_pairs)
    (every,) = ContactSolver(V, F).candidates(V, inflation=0.3)
    sets = solver.candidates(V, inflation=0.3)
    assert len(sets) == 2
    face_edges = [set(map(int, edges)) for edges in solver.mesh.faces_to_edges]
    ref_faces = intersecting_faces(ref_pairs, len(F))
    clean_edges = {e for f in np.flatnonzero(~ref_faces) for e in face_edges[f]}
    clean_vertices = set(F[~ref_faces].ravel().tolist())

    def edge_pairs(*cs):
        return [tuple(sorted((k.edge0_id, k.edge1_id))) for c in cs for k in c.ee_candidates]

    across_ee = {tuple(sorted((a, b))) for f, g in ref_pairs for a in face_edges[f] for b in face_edges[g]
                 if not {a, b} & clean_edges}  # one edge of each face of a pair, neither next to a clean face
    across_fv = {(int(f), int(v)) for p in ref_pairs for f, g in (p, p[::-1]) for v in F[g] if v not in clean_vertices}
    tolerated_ee = set(edge_pairs(every)) & across_ee
    tolerated_fv = {(c.face_id, c.vertex_id) for c in every.fv_candidates} & across_fv
    assert tolerated_ee and tolerated_fv
    fv_kept = [(c.face_id, c.vertex_id) for kept in sets for c in kept.fv_candidates]
    ee_kept = edge_pairs(*sets)
    assert len(set(ee_kept)) == len(ee_kept) and len(set(fv_kept)) == len(fv_kept)  # once each
    assert set(ee_kept) == set(edge_pairs(every)) - tolerated_ee
    assert set(fv_kept) == {(c.face_id, c.vertex_id) for c in every.fv_candidates} - tolerated_fv


def test_one_large_step_through_a_thin_wall_is_cut_by_ccd():
    wall = trimesh.creation.box(extents=[0.02, 4.0, 4.0])  # a thin wall at x = 0
    ball = sphere([-0.5, 0, 0], radius=0.2, subdivisions=1)
    V, F = union((np.asarray(wall.vertices), np.asarray(wall.faces)), ball)
    moving = np.arange(len(V)) >= len(wall.vertices)
    goal = V + np.where(moving[:, None], [1.0, 0, 0], [0, 0, 0])  # one step would jump to the other side
    weights = np.where(moving, 1.0, 1e6)
    r = ContactSolver(V, F, settings=ContactSettings(smoothing=0.0)).compute_pose(V, goal, weights)
    assert r.X[moving, 0].max() < -0.01  # still on its side, pressed against the wall
    assert r.X[moving, 0].max() > -0.02
    assert len(self_intersecting_pairs(r.X, F)) == 0


def test_a_step_of_many_edge_lengths_is_checked_in_substeps_up_to_its_first_contact():
    wall = trimesh.creation.box(extents=[0.02, 4.0, 4.0])  # faces at x = -0.01 and 0.01
    ball = sphere([-3.0, 0, 0], radius=0.2, subdivisions=2)  # leftmost at x = -3.2, edges about 0.06 long
    V, F = union((np.asarray(wall.vertices), np.asarray(wall.faces)), ball)
    solver = ContactSolver(V, F)
    moving = (np.arange(len(V)) >= len(wall.vertices))[:, None]
    X1 = V + moving * [5.0, 0.0, 0.0]  # through the wall, a move of 28 mean edge lengths (the wall's are 4 long)
    assert 5.0 / solver.edge_length > 20
    step = solver.collision_free_step(V, X1)
    assert 2.6 / 5.0 * 0.8 < step < 2.8 / 5.0  # the ball's front (x = -2.8) stops before x = -0.01
    assert solver.collision_free_step(V, V + moving * [2.0, 0.0, 0.0]) == 1.0  # clear of the wall all the way


def test_the_barrier_pairs_from_the_swept_candidates_are_those_of_a_broad_phase_at_the_point():
    """The line search's trial points take their barrier pairs from the candidates CCD swept for the step: the same
    pairs (an edge pair's edges in either order) as a broad phase of their own, so the same barrier, where CCD stops
    the ball before the wall and short of it."""
    wall = trimesh.creation.box(extents=[0.2, 4.0, 4.0])  # its face at x = -0.1
    ball = sphere([-0.5, 0, 0], radius=0.2, subdivisions=2)  # its front at x = -0.3
    V, F = union((np.asarray(wall.vertices), np.asarray(wall.faces)), ball)
    solver = ContactSolver(V, F, settings=ContactSettings(dhat=1e-2))  # dhat 0.022
    moving = (np.arange(len(V)) >= len(wall.vertices))[:, None]
    X1 = V + moving * [0.3, 0.0, 0.0]  # the front through the wall's face, in two substeps
    alpha, swept = solver.swept_step(V, X1)
    assert 0.0 < swept.a < alpha < swept.b == 1.0

    for t in (alpha, 0.5 * (swept.a + alpha)):
        X = V + t * (X1 - V)
        reused, own = solver.collisions(X, swept.sets), solver.collisions(X)
        assert sum(map(len, reused)) == sum(map(len, own))
        assert solver.barrier_terms(reused, X) == pytest.approx(solver.barrier_terms(own, X), rel=1e-12)
        assert np.allclose(solver.barrier_terms(reused, X, 1), solver.barrier_terms(own, X, 1), rtol=1e-12, atol=0)
    assert sum(map(len, solver.collisions(V + alpha * (X1 - V)))) > 10  # the front is within dhat of the wall there


def test_two_intersection_sites_of_the_reference_cannot_pass_through_each_other():
    """Two sites where the reference intersects itself, each a triangle T through a triangle U, 5 apart: all four
    faces are tolerated, yet T of the first site driven through U of the second stops at it (tolerating every
    pair of tolerated faces, as before, let it pass: pair (0, 3))."""
    T = np.array([[-0.5, -0.5, 0.0], [0.5, -0.5, 0.0], [0.0, 0.5, 0.0]])
    U = np.array([[0.0, -0.2, -0.5], [0.0, 0.2, -0.5], [0.0, 0.0, 0.5]])
    V, F = np.vstack([T, U, T + [5, 0, 0], U + [5, 0, 0]]), np.arange(12).reshape(4, 3)
    ref_pairs = self_intersecting_pairs(V, F)
    assert ref_pairs.tolist() == [[0, 1], [2, 3]]
    goal = V.copy()
    goal[:3] += [5.0, 0.0, 0.25]  # the first T through the second U
    r = ContactSolver(V, F, ref_pairs).compute_pose(V, goal, np.ones(len(V)))
    assert self_intersecting_pairs(r.X, F).tolist() == [[2, 3]]
    assert 4.9 < r.X[:3, 0].mean() < 5.0 and r.contact[:3].any()  # it travelled up to U


def test_a_start_in_contact_is_refused():
    V, F = union(sphere([-1.0, 0, 0]), sphere([1.0, 0, 0]))  # touching at x = 0
    V[np.argmax(V[:, 0] * (np.arange(len(V)) < len(V) // 2))] = 0.0
    V[len(V) // 2 + np.argmin(V[len(V) // 2:, 0])] = 0.0
    with pytest.raises(ValueError, match="not intersection-free"):
        ContactSolver(V, F, settings=ContactSettings(touching=0.0)).compute_pose(V, V, np.ones(len(V)))


def test_a_contact_at_the_float32_spacing_keeps_a_gap_that_survives_rounding():
    """Triangle B's corner 2e-8 above triangle A (coordinates about 1, float32 spacing 1.2e-7): rounded to float32
    as written, the corner ends on A's other side and the faces intersect; pushed by keep_gap, they stay apart."""
    from posefix.mesh.rounding import float32_gap
    V_ref, X, F = float32_crossing()
    rounded = X.astype(np.float32).astype(np.float64)
    assert len(self_intersecting_pairs(X, F)) == 0 and len(self_intersecting_pairs(rounded, F)) == 1
    movable = np.arange(6) >= 3
    Y, distance = ContactSolver(V_ref, F).keep_gap(X, movable)
    assert distance >= float32_gap(X)
    assert np.array_equal(Y[:3], X[:3]) and np.abs(Y - X).max() < 10 * float32_gap(X)
    assert len(self_intersecting_pairs(Y.astype(np.float32).astype(np.float64), F)) == 0
    assert np.array_equal(ContactSolver(V_ref, F).keep_gap(Y, movable)[0], Y)  # far enough: unchanged


def test_a_numerically_indefinite_newton_matrix_is_solved_with_its_diagonal_scaled_slightly():
    """A PSD matrix that Cholesky refuses (singular in floating point, as the barrier's Hessian at a stiffness of
    1e12 beside goal weights of 1e-6 was on cat-09) is solved with its diagonal scaled by 1 + 1e-12."""
    from posefix.mesh.contact_solver import _spd_solve
    H = sp.csc_matrix(np.array([[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1e-6]]))
    x = _spd_solve(H, np.array([1.0, 1.0, 1e-6]))
    assert np.allclose(x, [0.5, 0.5, 1.0], rtol=1e-9)
    assert np.allclose(_spd_solve(sp.csc_matrix(np.diag([2.0, 4.0])), np.array([2.0, 2.0])), [1.0, 0.5], rtol=0)


def test_the_solver_runs_ipctk_on_one_thread_so_that_the_same_inputs_give_the_same_result():
    """ipctk's parallel broad phase and barrier sums add up in an order that changes from run to run (lion-04's
    verify at 2 threads: two runs 1.7e-3 apart): the solver sets ipctk to one thread, whatever it was."""
    V, F = capsule(around=12, cap_rings=3, length_rings=6)
    ipctk.set_num_threads(2)
    solver = ContactSolver(V, F)
    assert ipctk.get_num_threads() == 1
    runs = [solver.compute_pose(V, V + [0.5, 0.0, 0.0], np.ones(len(V))).X for _ in range(2)]
    assert np.array_equal(*runs)
