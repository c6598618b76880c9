"""Numerical tolerances of the kernel and the methods, in one place.

Each is a property of float64 arithmetic, not of a mesh or a method: the tunable tolerances of a solver
(stopping criteria, thresholds relative to the bounding-box diagonal) are its settings, in ``config.yaml``.
The OpenCL integrator's kernel source (:mod:`posefix.spacetime.integration_opencl`) repeats ``ROUNDOFF``
and ``TINY`` as literals, as it mirrors :mod:`posefix.spacetime.integration`.
"""

TINY = 1e-300
"""Floor of a denominator that may be exactly zero (a norm, an area, a radius, a squared distance): the quotient
stays finite where the numerator is zero too; far below any length of a mesh, far above float64's smallest
normal number (2.2e-308)."""

ROUNDOFF = 1e-12
"""Relative size of the rounding that a few thousand float64 operations accumulate (about 1e4 machine epsilons):
two values closer than this (relative to their scale) are taken as equal. Integration times that reached their
target, the regularization of a solve where a part touches no fixed vertex, the pivots of the RBF fit's
factorization, a separating move that closed its gap, the smallest line-search step of the contact solver."""

SMALL_ANGLE = 1e-6
"""Rotation angles (radians) below which the rotation vector's exponential and logarithm use their Taylor series:
there the series' first omitted term (angle^4 / 120) is below float64's epsilon."""
