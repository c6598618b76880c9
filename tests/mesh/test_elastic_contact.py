"""The contact solver's elastic energy (ContactSolver.compute_elastic): rigid motions cost nothing."""

import contextlib

import numpy as np

from posefix.mesh.contact_solver import ContactSettings, ContactSolver
from posefix.mesh.distortion import face_distortion
from posefix.mesh.rotations import rotation_exp
from posefix.mesh.shells import rest_elastic_energy

from test_contact_solver import sphere, union


def test_a_rigid_rotation_of_a_free_part_comes_back_rigid():
    V, F = union(sphere([-1.5, 0, 0]), sphere([1.5, 0, 0]))
    right = np.arange(len(V)) >= len(V) // 2
    R = rotation_exp(np.array([[0.3, 1.2, -0.4]]))[0]
    goal = V.copy()
    goal[right] = (V[right] - [1.5, 0, 0]) @ R.T + [1.5, 0.5, 0]
    solver = ContactSolver(V, F, settings=ContactSettings(tolerance=1e-8))
    shell = rest_elastic_energy(V, F, V, 4.0, 1e-3)
    r = solver.compute_elastic(V, goal, np.full(len(V), 1e-2), shell, pinned=~right)
    edge, area = face_distortion(r.X, V, F)
    assert r.converged and np.abs(edge - 1.0).max() < 1e-6 and np.abs(area - 1.0).max() < 1e-6
    assert np.array_equal(r.X[~right], V[~right])
    assert np.abs(r.X - goal).max() < 1e-3 * solver.d


def test_the_elastic_energy_splits_into_groups_that_add_up_to_it():
    """Per group of vertices (the two spheres; then one of them alone), the goal terms of its vertices and the
    residuals that touch them: the groups of a partition add up to the whole energy."""
    V, F = union(sphere([-1.5, 0, 0]), sphere([1.5, 0, 0]))
    X = V * [1.2, 0.9, 1.0] + 0.01 * np.sin(np.arange(len(V)))[:, None]
    solver, shell = ContactSolver(V, F), rest_elastic_energy(V, F, V, 4.0, 1e-2)
    weights = np.full(len(V), 0.1)
    groups = (np.arange(len(V)) >= len(V) // 2).astype(int)
    parts = solver.elastic_energy(X, V, weights, shell, groups)
    total = solver.elastic_energy(X, V, weights, shell)
    assert parts.shape == (2,) and np.isclose(parts.sum(), total, rtol=1e-12) and (parts > 0).all()
    left = np.where(groups == 0, 0, -1)
    assert np.isclose(solver.elastic_energy(X, V, weights, shell, left)[0], parts[0], rtol=1e-12)


def test_an_elastic_solve_sees_only_the_pairs_and_terms_of_the_vertices_that_move(monkeypatch):
    """Two pinned spheres closer than dhat and a free one pushed onto the second: within the solve the broad phase
    keeps no pair of pinned vertices and the energy only the terms of the free one, and the result is the whole
    problem's (the restriction switched off)."""
    V, F = union(sphere([-1.5, 0, 0]), sphere([0.5005, 0, 0]), sphere([3.0, 0, 0]))
    third = len(V) // 3
    pinned = np.arange(len(V)) < 2 * third
    goal = V.copy()
    goal[~pinned] -= [0.6, 0.0, 0.0]  # into the second sphere
    solver = ContactSolver(V, F, settings=ContactSettings(tolerance=1e-8))
    shell = rest_elastic_energy(V, F, V, 4.0, 1e-2)
    assert solver.min_distance(V) < solver.dhat  # the pinned spheres' pairs are active at rest
    with solver._moving(~pinned):
        for c in solver.candidates(V, goal):
            E, Fc = solver.mesh.edges, solver.mesh.faces
            ee = np.array([(k.edge0_id, k.edge1_id) for k in c.ee_candidates]).reshape(-1, 2)
            fv = np.array([(k.face_id, k.vertex_id) for k in c.fv_candidates]).reshape(-1, 2)
            assert (~pinned[E[ee].reshape(len(ee), -1)]).any(axis=1).all()
            assert (~pinned[np.c_[Fc[fv[:, 0]], fv[:, 1]]]).any(axis=1).all() and len(fv) > 0
    weights = np.full(len(V), 0.1)
    r = solver.compute_elastic(V, goal, weights, shell, pinned=pinned)
    assert len(shell.restricted(~pinned).residuals(V)) < 0.4 * len(shell.residuals(V))
    monkeypatch.setattr(type(shell), "restricted", lambda self, moving: self)
    monkeypatch.setattr(type(solver), "_moving", lambda self, moving: contextlib.nullcontext())
    whole = solver.compute_elastic(V, goal, weights, shell, pinned=pinned)
    assert r.converged and whole.converged and np.array_equal(r.X[pinned], V[pinned])
    assert np.abs(r.X - whole.X).max() < 1e-6 * solver.d and r.min_distance > 0
    assert np.abs(r.X - goal)[~pinned].max() > 0.05  # the push held it
