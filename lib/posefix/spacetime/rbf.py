"""The space-time RBF vector field of S0 §4.2: ``f(y) = sum_j w_j phi(|y - g_j|) + pi(y)``.

``y`` in R^4 (space and scaled time), ``f(y)`` in R^3; ``phi(r) = r^2 ln r`` (``phi(0) = 0``, the
4D "triharmonic" kernel of S0) and ``pi`` a full quadratic polynomial in four variables (15 terms).

Points are handled in *normalized* coordinates ``z = (y - shift) / scale``. Because the quadratic
polynomial is part of the model, the interpolant does not depend on that affine map
(``phi(s r) = s^2 phi(r) + s^2 r^2 ln s`` and ``r^2`` is a quadratic in ``y``), while the
conditioning of the linear algebra does (see :data:`NORMALIZED_DIAGONAL`).
"""

from dataclasses import dataclass

import numpy as np
from scipy.spatial.distance import cdist

from posefix.mesh.tolerances import TINY

POLY_TERMS = 15
_PAIRS = [(i, j) for i in range(4) for j in range(i, 4)]


def kernel(r2):
    """``phi`` from squared distances: ``0.5 r^2 ln(r^2) = r^2 ln r``, with ``phi(0) = 0``.

    Parameters
    ----------
    r2 : ndarray
        Squared distances (non-negative).

    Returns
    -------
    ndarray, same shape (one allocation, in-place arithmetic)
    """
    phi = np.maximum(r2, TINY)
    np.log(phi, out=phi)
    phi *= r2
    phi *= 0.5
    return phi


def kernel_matrix(Za, Zb):
    """``phi(|za - zb|)`` for all pairs of rows, (len(Za), len(Zb)) float."""
    return kernel(cdist(Za, Zb, "sqeuclidean"))


def poly_basis(Z):
    """The 15 monomials ``1, z_i, z_i z_j (i <= j)`` at points (k, 4) -> (k, 15) float."""
    cols = [np.ones(len(Z))] + [Z[:, i] for i in range(4)] + [Z[:, i] * Z[:, j] for i, j in _PAIRS]
    return np.stack(cols, axis=1)


NORMALIZED_DIAGONAL = 3.0
"""Diagonal of the box the points are mapped into. The interpolant does not depend on it, the
condition number of the saddle-point system does: on lion-04 (3,000 centres) kappa_1 was 4.0e8 at
diagonal 1, 1.0e8 at 2, 6.6e7 at 3, 8.9e7 at 4 and 1.7e8 at 8."""


def normalization(points):
    """Shift and scale mapping ``points`` (k, 4) into a centred box of diagonal :data:`NORMALIZED_DIAGONAL`."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    return 0.5 * (lo + hi), (float(np.linalg.norm(hi - lo)) or 1.0) / NORMALIZED_DIAGONAL


@dataclass
class RBFField:
    """A fitted space-time vector field.

    Attributes
    ----------
    centers : (n, 4) float
        Centres ``g_j`` in space-time (length units; time scaled by ``tau``).
    weights : (n, 3) float
        Kernel weights ``w_j`` (in normalized coordinates).
    poly : (15, 3) float
        Polynomial coefficients (in normalized coordinates, monomial order of :func:`poly_basis`).
    shift : (4,) float
    scale : float
        Normalization ``z = (y - shift) / scale``.
    """

    centers: np.ndarray
    weights: np.ndarray
    poly: np.ndarray
    shift: np.ndarray
    scale: float

    def normalize(self, Y):
        """Normalized coordinates of space-time points (k, 4)."""
        return (np.asarray(Y, dtype=np.float64) - self.shift) / self.scale

    def __call__(self, Y, chunk=4096):
        """Field values at space-time points ``Y`` (k, 4) -> (k, 3), evaluated in chunks."""
        Z = self.normalize(Y)
        C = self.normalize(self.centers)
        out = np.empty((len(Z), 3))
        for start in range(0, len(Z), chunk):
            z = Z[start:start + chunk]
            out[start:start + chunk] = kernel_matrix(z, C) @ self.weights + poly_basis(z) @ self.poly
        return out
