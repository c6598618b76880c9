"""The shared tolerances keep the float64 properties their docstrings promise."""

import numpy as np

from posefix.mesh.rotations import rotation_exp, rotation_log
from posefix.mesh.tolerances import ROUNDOFF, SMALL_ANGLE, TINY


def test_tiny_is_a_normal_number_whose_inverse_is_finite():
    assert TINY > np.finfo(float).tiny and np.isfinite(1.0 / TINY)


def test_roundoff_is_thousands_of_machine_epsilons():
    assert 1e3 * np.finfo(float).eps < ROUNDOFF < 1e-9


def test_the_small_angle_series_is_exact_to_float64_on_both_sides_of_the_switch():
    assert SMALL_ANGLE ** 4 / 120 < np.finfo(float).eps
    for theta in (0.5 * SMALL_ANGLE, 2.0 * SMALL_ANGLE):
        omega = np.array([[theta, 0.0, 0.0]])
        R = rotation_exp(omega)[0]
        assert abs(R[1, 1] - np.cos(theta)) < 1e-16 and abs(R[2, 1] - np.sin(theta)) < 1e-16
        assert np.abs(rotation_log(R[None]) - omega).max() < 1e-16
