"""posefix: repair self-intersections in mesh pose libraries by space-time integration.

The Python API (``docs/api.md``): :func:`repair_library` runs the workflow on a pose library,
:func:`repair_pose` repairs one pose in memory, and both raise :class:`PosefixError` with a one-line message.

Conventions used throughout the package:

* ``V`` is a float64 array of shape (n, 3): vertex positions in the input's length units.
* ``F`` is an int64 array of shape (m, 3): triangle vertex indices, 0-based, never reordered.
* Lengths reported "relative" are divided by the reference's bounding-box diagonal ``d``.

Importing the package first (the stage scripts do) sets two runtime defaults before numpy loads,
unless the variables are already set (measured on our 2-core AMD EPYC machines, see
``reports/bench/``):

* ``NUMPY_MADVISE_HUGEPAGE=0``: with transparent huge pages in ``madvise`` mode, first touches of
  large fresh arrays were 6x slower with numpy's huge-page advice (3.2 GB: 9.0 s vs 1.5 s).
* ``OPENBLAS_CORETYPE=SkylakeX`` on CPUs with AVX-512: OpenBLAS otherwise picks its Haswell
  kernels there; dgemm ran at 100 instead of 56 GFLOP/s.
"""

import os

__version__ = "0.1.0"


def _avx512():
    """Whether the CPU advertises the AVX-512 subsets OpenBLAS's SkylakeX kernels use."""
    try:
        with open("/proc/cpuinfo") as fh:
            flags = next((line.split(":", 1)[1].split() for line in fh if line.startswith("flags")), [])
    except OSError:
        return False
    return {"avx512f", "avx512dq", "avx512bw", "avx512vl", "avx512cd"} <= set(flags)


def _runtime_defaults():
    os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")
    if "OPENBLAS_CORETYPE" not in os.environ and _avx512():
        os.environ["OPENBLAS_CORETYPE"] = "SkylakeX"


_runtime_defaults()


_API = {"repair_pose": "posefix.pose_repair", "repair_library": "posefix.workflow.library_repair",
        "PosefixError": "posefix.io.errors"}
"""The API's names and their modules, imported when first used (``import posefix`` loads no numpy: the runtime
defaults above must come first)."""


def __getattr__(name):
    if name not in _API:
        raise AttributeError(f"module 'posefix' has no attribute {name!r}")
    import importlib
    return getattr(importlib.import_module(_API[name]), name)


__all__ = ["__version__", *_API]
