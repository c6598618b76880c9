"""Work spread over spawned worker processes that die with their parent (the downstream check's runs, the poses of
a pose job)."""

import ctypes
import itertools
import multiprocessing
import os
import signal
import sys
from concurrent.futures import ProcessPoolExecutor

from threadpoolctl import threadpool_limits

PR_SET_PDEATHSIG = 1
"""Linux's ``prctl`` option: the signal a process gets when the thread that started it ends."""


def ordered_map(fn, jobs, workers):
    """``fn(*job)`` for every job of ``jobs`` (list of tuples), in order: one after the other, or in ``workers``
    spawned processes with one BLAS thread each (:func:`worker_start`). Yields the results."""
    if workers <= 1 or len(jobs) <= 1:
        yield from itertools.starmap(fn, jobs)
        return
    with ProcessPoolExecutor(min(workers, len(jobs)), mp_context=multiprocessing.get_context("spawn"),
                             initializer=worker_start, initargs=(os.getpid(),)) as pool:
        yield from pool.map(fn, *zip(*jobs))


def worker_start(parent):
    """A worker's set-up: one BLAS thread, and (Linux) SIGKILL when its parent, the process ``parent`` (pid), dies,
    however it dies: a killed stage leaves no worker behind. Exits at once where the parent is already gone (it
    died before the signal was asked for)."""
    threadpool_limits(1)
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
        if os.getppid() != parent:
            os._exit(1)
