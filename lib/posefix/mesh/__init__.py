"""The mesh kernel: method-agnostic geometry on ``V`` (n, 3) float64 and ``F`` (m, 3) int64.

Geometry, connectivity, Laplacians and harmonic extension, rotations, exact predicates, the box
tree, the exact self-intersection detector, near contacts and separating axes. Every method of
posefix builds on these; nothing here imports another part of posefix.
"""
