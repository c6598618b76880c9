"""Per-vertex flags of the repair (``verify.h5`` dataset ``replaced``): what happened to each vertex.

A bit field: a vertex may carry several flags (snapped onto the target, then pushed, ...).
:data:`FLAGS` is the one place their meanings are written: the stage's dataset description,
``docs/artifacts.md`` (a test compares them) and the report's legend take them from there.
"""

from dataclasses import dataclass

import numpy as np

REPLACED_PASS_THROUGH = 1
REPLACED_NEW_INTERSECTION = 2
SMOOTHED = 4
RIGID_REFERENCE = 8
REPRODUCED = 16
PUSHED = 32
SEPARATED = 64
CONTACT = 128


@dataclass(frozen=True)
class Flag:
    """One flag: its bit, a short label (legends, logs) and its meaning (documentation)."""

    bit: int
    label: str
    meaning: str


FLAGS = (
    Flag(REPLACED_PASS_THROUGH, "pass-through: target",
         "target (key frames pass through each other and integration did not reach the target, S0 Fig. 9)"),
    Flag(REPLACED_NEW_INTERSECTION, "new intersection: target",
         "target (the region had intersecting faces that the target does not have: new ones, or in the contact "
         "finish the reference's own where the target has undone them)"),
    Flag(SMOOTHED, "smoothed", "smoothed (unconstrained vertex, to untangle new intersecting faces)"),
    Flag(RIGID_REFERENCE, "rigid reference",
         "rigid reference (the reference's shape of the region moved rigidly onto it, to untangle new intersecting "
         "faces)"),
    Flag(REPRODUCED, "reproduced",
         "reproduced (moved onto the target if constrained, else by the harmonic blend of the constrained residual)"),
    Flag(PUSHED, "pushed out of a contact",
         "pushed (unconstrained vertex pushed out of a contact that putting V_C on its targets makes)"),
    Flag(SEPARATED, "separated",
         "separated (moved apart from a face it newly intersects, along the axis that separates the two in the "
         "reference)"),
    Flag(CONTACT, "held by a contact",
         "held by a contact (the contact finish's barrier holds the vertex off its goal: it is closer than dhat to a "
         "part it does not touch in the reference)"),
)
"""Every flag, in bit order."""

SNAP = REPRODUCED | PUSHED | CONTACT
"""Flags of the finish that puts ``V_C`` onto the target, by the snap or by the contact solver (not a fallback)."""
UNTANGLED = REPLACED_NEW_INTERSECTION | SMOOTHED | RIGID_REFERENCE | SEPARATED
"""Flags of the new-intersection remedies."""


def describe_flags():
    """The meaning of every flag as one line, ``"1 target (...), 2 ..."``, str."""
    return ", ".join(f"{f.bit} {f.meaning}" for f in FLAGS)


def flag_counts(replaced, new, F):
    """Vertex counts per kind of flag and the new faces inside pass-through regions.

    Parameters
    ----------
    replaced : (n,) uint8
        Flags per vertex.
    new : (m,) bool
        New intersecting faces of the repaired pose.
    F : (m, 3) int

    Returns
    -------
    dict of str -> int
        ``fallback_vertices`` (any flag but the snap's), ``fallback_pass_through``,
        ``fallback_new_intersection`` (:data:`UNTANGLED`), ``reproduced_vertices``,
        ``pushed_vertices`` and ``repaired_new_in_fallback`` (new faces with a pass-through vertex).
    """
    pass_through = (replaced & REPLACED_PASS_THROUGH) > 0
    return {"fallback_vertices": int(np.count_nonzero(replaced & ~np.uint8(SNAP))),
            "fallback_pass_through": int(np.count_nonzero(pass_through)),
            "fallback_new_intersection": int(np.count_nonzero(replaced & np.uint8(UNTANGLED))),
            "reproduced_vertices": int(np.count_nonzero(replaced & REPRODUCED)),
            "pushed_vertices": int(np.count_nonzero(replaced & PUSHED)),
            "repaired_new_in_fallback": int(new[pass_through[F].any(axis=1)].sum())}
