"""The contact solver's elastic energy (ContactSolver.compute_elastic): rigid motions cost nothing."""

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
