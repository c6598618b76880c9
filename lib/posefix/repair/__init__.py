"""Verification of an integrated pose and the repairs after it, as one sequence
(:func:`posefix.repair.sequence.repair_pose`).

Snap of ``V_C`` onto the target (:mod:`~posefix.repair.reproduce`), the pass-through fallback to
the target (:mod:`~posefix.repair.fallback`), untangling of new intersections
(:mod:`~posefix.repair.untangle`), deviation metrics (:mod:`~posefix.repair.deviation`) and the
per-vertex flags that record what happened (:mod:`~posefix.repair.flags`).
"""
