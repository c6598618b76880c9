"""Plumbing of the workflow: stage command lines, HDF5 artifacts, mesh files and pose libraries,
atomic file writing, fit checkpoints and the built-in demo library. All file I/O of posefix is here."""
