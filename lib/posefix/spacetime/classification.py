"""Vertex classification (S0 §4.1): which vertices constrain the space-time vector field.

``V_C`` starts as every vertex. Removed are (S0 §4.1)

* the vertices of every face that intersects in any key frame, grown by ``ring`` rings;
* optionally, near-contact vertices (:mod:`posefix.mesh.contacts`) of any key frame, grown the same way
  (beyond S0);
* vertices the user excludes by hand (S0 Fig. 4b), without ring growth.

Then, as in S0 §4.3, the vertices of faces that already intersect in the reference are added back
(unless excluded by hand): the reference's own intersections are reproduced, not repaired, and do
not cost the rest of the mesh its constraints. Their surrounding rings stay excluded.

The reason each vertex left or re-entered ``V_C`` is kept as a bit field (``EXCLUDED_*`` flags).
"""

import numpy as np

from posefix.mesh.intersections import intersecting_faces
from posefix.mesh.topology import grow_rings, vertex_adjacency

EXCLUDED_INTERSECTION = 1
"""Vertex of a face that intersects in some key frame."""
EXCLUDED_RING = 2
"""Within ``ring`` rings of an intersecting or contact vertex."""
EXCLUDED_CONTACT = 4
"""Near contact in some key frame."""
EXCLUDED_MANUAL = 8
"""Excluded by the user."""
READDED_REFERENCE = 16
"""Vertex of a face that intersects in the reference: in ``V_C`` unless excluded by hand."""


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
    hit = np.zeros(n, dtype=bool)
    for pairs in frame_pairs:
        hit[F[intersecting_faces(pairs, m)].ravel()] = True
    contact = contacts.any(axis=0) if contacts is not None else np.zeros(n, dtype=bool)
    manual = np.zeros(n, dtype=bool)
    manual[np.asarray(exclude, dtype=np.int64)] = True
    seeds = hit | contact
    ringed = grow_rings(seeds, vertex_adjacency(F, n), ring) & ~seeds
    readd = np.zeros(n, dtype=bool)
    readd[F[intersecting_faces(frame_pairs[0], m)].ravel()] = True
    readd &= ~manual
    mask = (~(seeds | ringed | manual)) | readd
    reasons = (hit * EXCLUDED_INTERSECTION | ringed * EXCLUDED_RING | contact * EXCLUDED_CONTACT
               | manual * EXCLUDED_MANUAL | readd * READDED_REFERENCE).astype(np.uint8)
    return mask, reasons


def split_frames(pairs, offsets):
    """Intersecting pairs per key frame from their concatenation (classify.h5 ``pairs``, ``pair_offsets``).

    Parameters
    ----------
    pairs : (P, 2) int
    offsets : (K + 1,) int
        Frame ``k`` has ``pairs[offsets[k]:offsets[k + 1]]``.

    Returns
    -------
    list of K (k_i, 2) int arrays
    """
    return [pairs[offsets[k]:offsets[k + 1]] for k in range(len(offsets) - 1)]

