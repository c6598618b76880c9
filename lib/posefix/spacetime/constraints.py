"""Space-time constraints from vertex trajectories (S0 §4.1, "Space-time constraint generation").

Each vertex of ``V_C`` moves along a C1 cubic trajectory ``c(t)`` through its key-frame positions
``x(t_k)``. Its tangents at the knots are either

* ``hermite`` (S0): finite differences in time, central inside, one-sided at ``t = 0`` and ``1``;
* ``spline``: those of the C2 cubic spline through the knots with not-a-knot ends (the one-sided
  end differences of ``hermite`` are only first-order accurate).

Sampling ``c`` at ``t_i = i / s`` gives the constraints: space-time points
``y = (c(t_i), tau * t_i)`` in R^4 (``tau`` in length units scales the time axis) and tangents
``c'(t_i)`` in R^3 (length per unit time) that the vector field must interpolate.
"""

import numpy as np
from scipy.interpolate import CubicSpline


def knot_tangents(frames, t, method="spline"):
    """Tangents of the trajectories at the key frames.

    Parameters
    ----------
    frames : (K, n, 3) float
        Key-frame positions.
    t : (K,) float
        Strictly increasing key-frame times.
    method : {"hermite", "spline"}

    Returns
    -------
    (K, n, 3) float
        Velocities in length per unit time.
    """
    if method == "spline":
        return CubicSpline(t, frames, axis=0, bc_type="not-a-knot" if len(t) > 3 else "natural")(t, 1)
    if method != "hermite":
        raise ValueError(f"unknown tangent method {method!r}")
    D = np.empty_like(frames)
    D[0] = (frames[1] - frames[0]) / (t[1] - t[0])
    D[-1] = (frames[-1] - frames[-2]) / (t[-1] - t[-2])
    D[1:-1] = (frames[2:] - frames[:-2]) / (t[2:] - t[:-2])[:, None, None]
    return D


def hermite_sample(frames, tangents, t, times):
    """Evaluate the piecewise cubic Hermite trajectories and their derivatives.

    Parameters
    ----------
    frames, tangents : (K, n, 3) float
        Knot positions and tangents.
    t : (K,) float
        Knot times.
    times : (S,) float
        Sample times in ``[t[0], t[-1]]``.

    Returns
    -------
    positions, velocities : (S, n, 3) float
    """
    k = np.clip(np.searchsorted(t, times, side="right") - 1, 0, len(t) - 2)
    h = (t[k + 1] - t[k])[:, None, None]
    u = ((times - t[k]) / (t[k + 1] - t[k]))[:, None, None]
    p0, p1, m0, m1 = frames[k], frames[k + 1], tangents[k] * h, tangents[k + 1] * h
    u2, u3 = u * u, u * u * u
    pos = (2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * m0 + (-2 * u3 + 3 * u2) * p1 + (u3 - u2) * m1
    vel = ((6 * u2 - 6 * u) * p0 + (3 * u2 - 4 * u + 1) * m0 + (-6 * u2 + 6 * u) * p1 + (3 * u2 - 2 * u) * m1) / h
    return pos, vel


def spacetime_constraints(frames, t, mask, samples=12, *, tau, tangents="spline"):
    """Interpolation constraints of the space-time vector field.

    Parameters
    ----------
    frames : (K, n, 3) float
        Key frames.
    t : (K,) float
        Key-frame times, ``t[0] = 0``, ``t[-1] = 1``.
    mask : (n,) bool
        ``V_C``: vertices that generate constraints.
    samples : int
        ``s``: constraints at ``t_i = i / s``, ``i = 0..s`` (``s >= 2``).
    tau : float
        Time-axis scale in length units (the pipeline's is ``constraints.tau`` times the bbox diagonal).
    tangents : {"hermite", "spline"}

    Returns
    -------
    points : (N, 4) float
        ``(c(t_i), tau t_i)``, ordered by sample time, then vertex; ``N = (s + 1) |V_C|``.
    values : (N, 3) float
        Tangents ``c'(t_i)``.
    vertex : (N,) int64
        Vertex index of each constraint.
    time : (N,) float
        ``t_i`` of each constraint.
    """
    if samples < 2:
        raise ValueError("samples must be >= 2 (with t in {0, 1} only, t and t^2 coincide)")
    ids = np.flatnonzero(mask)
    sub = frames[:, ids]
    times = np.arange(samples + 1) / samples
    pos, vel = hermite_sample(sub, knot_tangents(sub, t, tangents), t, times)
    S, n = len(times), len(ids)
    time = np.repeat(times, n)
    points = np.concatenate([pos.reshape(-1, 3), (tau * time)[:, None]], axis=1)
    return points, vel.reshape(-1, 3), np.tile(ids, S).astype(np.int64), time
