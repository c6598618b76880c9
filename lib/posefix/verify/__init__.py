"""Verification of an integrated pose and the repairs after it, as one sequence
(:func:`posefix.verify.sequence.repair_pose`).

Snap of ``V_C`` onto the target (:mod:`~posefix.verify.reproduce`), the pass-through fallback to
the target (:mod:`~posefix.verify.fallback`), untangling of new intersections
(:mod:`~posefix.verify.untangle`), deviation metrics (:mod:`~posefix.verify.deviation`) and the
per-vertex flags that record what happened (:mod:`~posefix.verify.flags`).
"""
