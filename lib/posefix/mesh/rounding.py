"""How far rounding positions to float32 (USD ``point3f``, glTF accessors) can move primitives toward each other."""

import numpy as np

GAP_ULPS = 4.0
"""The gap :func:`float32_gap` keeps, in float32 spacings: rounding moves a point by at most ``sqrt(3) / 2`` of
one, so two primitives by at most ``sqrt(3)`` (1.73) toward each other."""


def float32_gap(V):
    """The distance between two primitives of ``V`` that rounding its coordinates to float32 cannot close.

    Parameters
    ----------
    V : (n, 3) float
        Positions (length units).

    Returns
    -------
    float
        ``GAP_ULPS`` float32 spacings at the largest coordinate magnitude (length units): the spacing there
        bounds the rounding of every coordinate, so pairs at least this far apart stay apart once rounded.

    Examples
    --------
    >>> float(float32_gap(np.array([[0.0, 0.0, 1.5]]))) == 4 * 2.0 ** -23
    True
    """
    return GAP_ULPS * float(np.spacing(np.float32(np.abs(V).max())))
