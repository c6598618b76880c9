"""Space-time constraints: trajectories through key frames, tangents, sampling layout."""

import numpy as np
import pytest

from posefix.spacetime.constraints import hermite_sample, knot_tangents, spacetime_constraints


def _frames(fn, K=11, n=7):
    rng = np.random.default_rng(0)
    x0, a, b, c = (rng.normal(size=(n, 3)) for _ in range(4))
    t = np.linspace(0, 1, K)
    return t, np.stack([fn(x0, a, b, c, ti) for ti in t])


@pytest.mark.parametrize("tangents", ["hermite", "spline"])
def test_straight_line_motion_gives_constant_tangents(tangents):
    t, frames = _frames(lambda x0, a, b, c, ti: x0 + ti * a)
    mask = np.ones(frames.shape[1], dtype=bool)
    points, values, vertex, time = spacetime_constraints(frames, t, mask, samples=12, tau=2.0, tangents=tangents)
    velocity = frames[-1] - frames[0]
    assert np.allclose(values, velocity[vertex], atol=1e-12)
    assert np.allclose(points[:, :3], frames[0][vertex] + time[:, None] * velocity[vertex], atol=1e-12)
    assert np.allclose(points[:, 3], 2.0 * time)


def test_spline_tangents_reproduce_cubic_motion_hermite_only_quadratic_inside():
    t, cubic = _frames(lambda x0, a, b, c, ti: x0 + ti * a + ti ** 2 * b + ti ** 3 * c)
    times = np.linspace(0, 1, 13)
    exact_v = lambda x0, a, b, c, ti: a + 2 * ti * b + 3 * ti ** 2 * c  # noqa: E731
    rng = np.random.default_rng(0)
    x0, a, b, c = (rng.normal(size=(7, 3)) for _ in range(4))
    pos, vel = hermite_sample(cubic, knot_tangents(cubic, t, "spline"), t, times)
    assert np.allclose(vel, np.stack([exact_v(x0, a, b, c, ti) for ti in times]), atol=1e-10)
    assert np.allclose(pos[[0, -1]], cubic[[0, -1]], atol=1e-14)
    _, quad = _frames(lambda x0, a, b, c, ti: x0 + ti * a + ti ** 2 * b)
    D = knot_tangents(quad, t, "hermite")
    assert np.allclose(D[1:-1], np.stack([a + 2 * ti * b for ti in t[1:-1]]), atol=1e-12)  # central: exact
    assert not np.allclose(D[0], a, atol=1e-3)  # one-sided end difference: first order only


def test_trajectories_interpolate_the_key_frames():
    t, frames = _frames(lambda x0, a, b, c, ti: x0 + np.sin(3 * ti) * a + np.cos(5 * ti) * b)
    for method in ("hermite", "spline"):
        pos, _ = hermite_sample(frames, knot_tangents(frames, t, method), t, t)
        assert np.allclose(pos, frames, atol=1e-14)


def test_only_vc_vertices_make_constraints_in_time_major_order():
    t, frames = _frames(lambda x0, a, b, c, ti: x0 + ti * a, n=5)
    mask = np.array([True, False, True, True, False])
    points, values, vertex, time = spacetime_constraints(frames, t, mask, samples=4, tau=1.0, tangents="hermite")
    assert len(points) == 5 * 3
    assert vertex.tolist() == [0, 2, 3] * 5
    assert np.allclose(time, np.repeat(np.arange(5) / 4, 3))
    with pytest.raises(ValueError, match="samples must be >= 2"):
        spacetime_constraints(frames, t, mask, samples=1, tau=1.0)
