"""Vertex classification (S0 §4.1): which vertices constrain the space-time vector field.

``V_C`` starts as every vertex. Removed are

* the vertices of faces in a **new** intersecting pair in any key frame (a pair of faces that
  does not already intersect in the reference, frame 0), grown by ``ring`` rings;
* optionally, near-contact vertices (:mod:`posefix.contacts`) of any key frame that are not
  already in contact in the reference, grown by ``ring`` rings;
* vertices the user excludes by hand (S0 Fig. 4b), without ring growth.

Then, as in S0 §4.3, vertices of faces that already intersect in the reference are added back
unless they belong to a new pair themselves or were excluded by hand: the reference's own
intersections are reproduced, not repaired.

The reason each vertex left or re-entered ``V_C`` is kept as a bit field (``EXCLUDED_*`` flags).
"""

import numpy as np

from posefix.intersections import intersecting_faces
from posefix.topology import grow_rings, vertex_adjacency

EXCLUDED_INTERSECTION = 1
"""Vertex of a face in a new intersecting pair in some key frame."""
EXCLUDED_RING = 2
"""Within ``ring`` rings of an intersecting or contact vertex."""
EXCLUDED_CONTACT = 4
"""Near contact in some key frame."""
EXCLUDED_MANUAL = 8
"""Excluded by the user."""
READDED_REFERENCE = 16
"""Vertex of a face that intersects in the reference, kept in ``V_C``."""


def new_pairs(pairs, reference_pairs):
    """Rows of ``pairs`` (k, 2) that are not in ``reference_pairs``; both sorted with ``f < g``."""
    if len(pairs) == 0 or len(reference_pairs) == 0:
        return pairs
    width = np.int64(max(pairs.max(), reference_pairs.max()) + 1)
    return pairs[~np.isin(pairs[:, 0] * width + pairs[:, 1], reference_pairs[:, 0] * width + reference_pairs[:, 1])]


def constraint_mask(F, n, frame_pairs, ring=1, contacts=None, exclude=()):
    """The constrained vertex set ``V_C``.

    Parameters
    ----------
    F : (m, 3) int
    n : int
        Number of vertices.
    frame_pairs : list of (k_i, 2) int
        Intersecting face pairs per key frame; frame 0 is the reference.
    ring : int
        Rings of neighbours removed around intersecting (and contact) vertices.
    contacts : (K, n) bool, optional
        Near-contact vertices per key frame.
    exclude : sequence of int
        Vertex ids to remove by hand.

    Returns
    -------
    mask : (n,) bool
        True for vertices in ``V_C``.
    reasons : (n,) uint8
        Bit field of ``EXCLUDED_*`` / ``READDED_REFERENCE`` flags.
    """
    m = len(F)
    reference = frame_pairs[0]
    hit_faces = np.zeros(m, dtype=bool)
    for pairs in frame_pairs[1:]:
        hit_faces |= intersecting_faces(new_pairs(pairs, reference), m)
    hit = np.zeros(n, dtype=bool)
    hit[F[hit_faces].ravel()] = True
    contact = np.zeros(n, dtype=bool)
    if contacts is not None:
        contact = contacts[1:].any(axis=0) & ~contacts[0]
    manual = np.zeros(n, dtype=bool)
    manual[np.asarray(exclude, dtype=np.int64)] = True
    seeds = hit | contact
    ringed = grow_rings(seeds, vertex_adjacency(F, n), ring) & ~seeds
    ref_faces = intersecting_faces(reference, m)
    readd = np.zeros(n, dtype=bool)
    readd[F[ref_faces].ravel()] = True
    readd &= ~hit & ~manual
    excluded = (seeds | ringed | manual) & ~readd
    reasons = (hit * EXCLUDED_INTERSECTION | ringed * EXCLUDED_RING | contact * EXCLUDED_CONTACT
               | manual * EXCLUDED_MANUAL | readd * READDED_REFERENCE).astype(np.uint8)
    return ~excluded, reasons
