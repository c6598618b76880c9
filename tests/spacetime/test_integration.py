"""Space-time integration: analytic fields, sample-time landing, OpenCL against numpy."""

import numpy as np
import pytest

from posefix.mesh.rotations import rotation_exp
from posefix.spacetime.integration import rk45


@pytest.mark.parametrize("tol", [1e-6, 1e-10])
def test_rotation_field_matches_its_closed_form(tol):
    w = np.array([0.3, -1.2, 2.0])
    X0 = np.random.default_rng(0).normal(size=(400, 3))
    times = np.linspace(0, 1, 5)
    X1, samples, steps, _ = rk45(lambda X, t: np.cross(w, X), X0, rtol=tol, atol=tol, sample_times=times)
    for ti, S in zip(times, samples):
        exact = X0 @ rotation_exp((ti * w)[None])[0].T
        assert np.abs(S - exact).max() <= 100 * tol
    assert np.array_equal(X1, samples[-1]) and (steps >= len(times) - 1).all()


def test_time_dependent_field():
    X0 = np.random.default_rng(1).normal(size=(50, 3))
    X1, _, _, _ = rk45(lambda X, t: 2 * t[:, None] * X, X0, rtol=1e-11, atol=1e-11)
    assert np.allclose(X1, X0 * np.e, rtol=1e-9, atol=0)
