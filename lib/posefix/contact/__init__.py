"""The contact repair: the IPC contact solver (:mod:`posefix.mesh.contact_solver`) carries the reference through
S0's key frames to the target, as IPC-based tools (Houdini's Detangle, Maya nCloth) move an intersection-free
state toward a deformed one (Li et al. 2020)."""
