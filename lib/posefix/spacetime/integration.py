"""Space-time integration of the reference vertices through the fitted field (S0 §4.3).

Every vertex follows ``dx/dt = f(x, tau t)`` from ``t = 0`` to ``1`` with the embedded Runge-Kutta
5(4) pair of Dormand and Prince and its own adaptive step size (vectorized over vertices: all
unfinished vertices take one step at a time, each with its own ``h``). A step is accepted when
``max_i |e_i| / (atol + rtol max(|x_i|, |x_new_i|)) <= 1`` (``e`` the difference of the 5th- and
4th-order solutions); the next step is ``h * min(5, max(0.2, 0.9 err^(-1/5)))``.
"""

import numpy as np

from posefix.mesh.tolerances import ROUNDOFF

# Dormand-Prince 5(4) tableau
_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
_A = [
    [],
    [1 / 5],
    [3 / 40, 9 / 40],
    [44 / 45, -56 / 15, 32 / 9],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
    [35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84],
]
_B5 = np.array([35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0.0])
_B4 = np.array([5179 / 57600, 0.0, 7571 / 16695, 393 / 640, -92097 / 339200, 187 / 2100, 1 / 40])
_E = _B5 - _B4

MAX_STEPS = 10000
"""Attempted steps per point at most (:func:`rk45` and the OpenCL kernel)."""


def rk45(velocity, X0, *, atol, rtol=1e-9, h0=0.05, sample_times=(0.0, 1.0)):
    """Integrate ``dx/dt = velocity(x, t)`` for many points from ``t = 0`` to ``t = 1``.

    Parameters
    ----------
    velocity : callable
        ``(X (k, 3), t (k,)) -> (k, 3)``: the field at points and their own times.
    X0 : (n, 3) float
        Start positions.
    atol, rtol : float
        Absolute (length units; the pipeline's: ``integrate.atol_rel`` d) and relative error tolerances per step.
    h0 : float
        First step size (time units).
    sample_times : sequence of float
        Increasing times in [0, 1] at which positions are recorded (steps are shortened to land on them).

    Returns
    -------
    X1 (n, 3) float, samples (S, n, 3) float, steps (n,) int, rejected (n,) int
        Positions at ``t = 1`` and at the sample times; accepted and rejected steps per point.
    """
    X = np.array(X0, dtype=np.float64)
    n, times = len(X), np.asarray(sample_times, dtype=np.float64)
    samples, t, h = np.empty((len(times), n, 3)), np.zeros(n), np.full(n, float(h0))
    steps, rejected, nxt = (np.zeros(n, dtype=np.int64) for _ in range(3))
    while (nxt < len(times)).any() and times[min(nxt.min(), len(times) - 1)] <= 0.0:
        _land(np.flatnonzero((nxt < len(times)) & (times[np.minimum(nxt, len(times) - 1)] <= 0.0)), X, t, times,
              (samples, nxt))
    k1 = velocity(X, t)
    active = np.arange(n)
    while len(active):
        x, tt = X[active], t[active]
        target = np.where(nxt[active] < len(times), times[np.minimum(nxt[active], len(times) - 1)], 1.0)
        hh = np.minimum(h[active], np.minimum(1.0, target) - tt)
        x5, err_vec, k7 = _dormand_prince_step(velocity, x, tt, hh, k1[active])
        scale = atol + rtol * np.maximum(np.abs(x), np.abs(x5))
        err = np.max(np.abs(err_vec) / scale, axis=1)
        ok = err <= 1.0
        acc = active[ok]
        X[acc], t[acc], k1[acc] = x5[ok], tt[ok] + hh[ok], k7[ok]   # FSAL: k7 is the next k1
        steps[acc] += 1
        rejected[active[~ok]] += 1
        _land(acc[(nxt[acc] < len(times)) & (t[acc] >= target[ok] - ROUNDOFF)], X, t, times, (samples, nxt))
        factor = np.clip(0.9 * np.maximum(err, 1e-10) ** -0.2, 0.2, 5.0)
        h[active] = hh * np.where(ok, factor, np.minimum(factor, 1.0))
        done = (t >= 1.0 - ROUNDOFF) | (steps + rejected >= MAX_STEPS)
        active = np.flatnonzero(~done)
    return X, samples, steps, rejected


def _land(points, X, t, times, record):
    """Record the ``points`` (k,) at their next sample time: their times ``t`` (n,) set to it, their positions
    ``X`` (n, 3) into ``record = (samples (S, n, 3), next sample (n,))``, and their next sample advanced."""
    samples, nxt = record
    t[points] = times[nxt[points]]
    samples[nxt[points], points] = X[points]
    nxt[points] += 1


def _dormand_prince_step(velocity, x, t, h, k1):
    """One Dormand–Prince 5(4) step of every point: ``(x5 (k, 3), error estimate (k, 3), k7 (k, 3))`` from positions
    ``x`` (k, 3) at times ``t`` (k,) with steps ``h`` (k,) and the field ``k1`` (k, 3) there (k7: the field at
    ``x5``, the next step's k1)."""
    K = [k1]
    for s in range(1, 7):
        xs = x + h[:, None] * sum(a * K[j] for j, a in enumerate(_A[s]) if a != 0.0)
        K.append(velocity(xs, t + _C[s] * h))
    x5 = x + h[:, None] * sum(b * K[j] for j, b in enumerate(_B5) if b != 0.0)
    return x5, h[:, None] * sum(e * K[j] for j, e in enumerate(_E) if e != 0.0), K[6]


def field_velocity(field, tau, chunk=2048):
    """Adapter: ``(X, t) -> field((X, tau t))`` for :func:`rk45` (``field`` an :class:`RBFField`)."""

    def velocity(X, t):
        return field(np.concatenate([X, (tau * t)[:, None]], axis=1), chunk=chunk)

    return velocity
