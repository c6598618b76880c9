"""posefix: repair self-intersections in mesh pose libraries by space-time integration.

Conventions used throughout the package:

* ``V`` is a float64 array of shape (n, 3): vertex positions in the input's length units.
* ``F`` is an int64 array of shape (m, 3): triangle vertex indices, 0-based, never reordered.
* Lengths reported "relative" are divided by the reference's bounding-box diagonal ``d``.
"""

__version__ = "0.1.0"
