"""What the machine gives a stage: an OpenCL device, and memory for caches.

Both are chosen once, at the start of a stage, and logged; a device asked for by name is checked before a local run
starts (:func:`device_problems`).
"""

import logging
import os

from posefix.io.errors import InputError

log = logging.getLogger(__name__)


def opencl_device(kind, threads):
    """The OpenCL device a stage asked for.

    Caps PoCL's worker threads at ``threads`` (before the OpenCL runtime starts). An explicit
    ``cpu`` or ``gpu`` request is honoured or fails; ``auto`` falls back to numpy with a warning.

    Parameters
    ----------
    kind : {"auto", "cpu", "gpu", "numpy"}
    threads : int
        Threads of the rule.

    Returns
    -------
    device : pyopencl.Device or None
        None for ``numpy``, or ``auto`` without a usable device.
    text : str
        ``"<platform>: <device>"``, or ``"numpy (CPU)"``.

    Raises
    ------
    InputError
        ``cpu`` or ``gpu`` requested but not available.
    """
    if kind == "numpy":
        return None, "numpy (CPU)"
    os.environ.setdefault("POCL_MAX_PTHREAD_COUNT", str(max(1, threads)))
    from posefix.spacetime.integration_opencl import select_device
    device, text = select_device(kind)
    if device is None and kind != "auto":
        raise InputError("--device", f"{kind} requested but {text} (use auto to fall back to numpy)")
    if device is None:
        log.warning("WARNING: %s; using the numpy backend instead (slower)", text)
        return None, "numpy (CPU)"
    return device, text


def device_problems(config):
    """The OpenCL devices config asks for by name (``fit.device``, ``integrate.device``: cpu or gpu) that this
    machine does not have: one line per setting, naming it (list of str; empty when all are there). For a run whose
    jobs run here; a cluster's nodes may have what the submitting machine lacks.

    Examples
    --------
    >>> device_problems({"fit": {"device": "auto"}, "integrate": {"device": "numpy"}})
    []
    """
    problems = []
    for section in ("fit", "integrate"):
        kind = config.get(section, {}).get("device", "auto")
        if kind in ("cpu", "gpu"):
            from posefix.spacetime.integration_opencl import select_device
            device, text = select_device(kind)
            if device is None:
                problems.append(f"{section}.device: {kind} requested but {text} (auto falls back to numpy)")
    return problems


def available_memory():
    """Bytes of memory available to a new allocation now (``MemAvailable``; all physical memory where unknown)."""
    try:
        with open("/proc/meminfo") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def cache_budget(requested, mem_mb, other, available=None):
    """Bytes a stage may spend on a cache.

    The smallest of the configured budget, the job's memory (``resources.mem_mb``) less what the
    stage needs besides the cache, and 80 % of the memory available now less the same; a warning
    when the machine, not the configuration, sets it (results may then differ from a run with the
    whole cache in the last bits).

    Parameters
    ----------
    requested : float
        Configured budget (bytes).
    mem_mb : float or None
        The job's memory in MB (None: no limit).
    other : float
        Bytes the stage needs besides the cache.
    available : float, optional
        Default: :func:`available_memory`.

    Returns
    -------
    float
        Bytes, at least 0.
    """
    available = available_memory() if available is None else available
    job = float("inf") if mem_mb is None else mem_mb * 1e6 - other
    machine = 0.8 * available - other
    budget = max(0.0, min(requested, job, machine))
    if machine < min(requested, job):
        log.warning("WARNING: only %.1f GB available: the cache budget drops from %.1f to %.1f GB",
                    available / 1e9, min(requested, job) / 1e9, budget / 1e9)
    return budget
