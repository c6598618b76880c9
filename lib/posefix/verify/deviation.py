"""Deviation of a repaired pose from its target, per vertex and summarized over ``V_C`` and the rest."""

import numpy as np


def deviation(X, V_tgt, mask, d):
    """Per-vertex deviation from the target relative to ``d`` and its summary over ``V_C`` and the rest.

    Parameters
    ----------
    X, V_tgt : (n, 3) float
        Repaired (or integrated) and target positions.
    mask : (n,) bool
        ``V_C``.
    d : float
        Length the deviations are divided by (the reference's bounding-box diagonal).

    Returns
    -------
    dev : (n,) float
        ``|X - V_tgt| / d``.
    summary : dict
        ``constrained_{max,mean,p95}`` and ``free_{max,mean,p95}`` (0 for an empty set).

    Examples
    --------
    >>> dev, s = deviation(np.zeros((2, 3)), np.array([[0.0, 0, 2], [0, 0, 4]]), np.array([True, False]), 2.0)
    >>> dev.tolist(), s["constrained_max"], s["free_max"]
    ([1.0, 2.0], 1.0, 2.0)
    """
    dev = np.linalg.norm(X - V_tgt, axis=1) / d
    summary = {}
    for name, sel in (("constrained", mask), ("free", ~mask)):
        part = dev[sel]
        summary[f"{name}_max"] = float(part.max()) if len(part) else 0.0
        summary[f"{name}_mean"] = float(part.mean()) if len(part) else 0.0
        summary[f"{name}_p95"] = float(np.percentile(part, 95)) if len(part) else 0.0
    return dev, summary
