"""Crash-safe checkpoints of a greedy fit (file I/O).

A checkpoint is a folder next to the fit's output::

    fit.checkpoint/meta.json          key, settings, history (one record per committed iteration)
    fit.checkpoint/iter-00000.npz     what iteration 0 added: centre indices, factor block, ...
    fit.checkpoint/iter-00001.npz     ...

Every file is written to a temporary name and renamed; ``meta.json`` is rewritten last, so it is
the commit record: a kill at any moment leaves either the previous or the new iteration
committed, never a half-written one. Everything the fit's state holds is append-only
(:meth:`posefix.spacetime.fit.GreedyFit.state`), so each iteration stores only its delta.

:func:`start_or_resume` continues a checkpoint where that gives exactly what an uninterrupted fit
with the same settings gives (:func:`posefix.spacetime.fit.truncate_history`), and
:func:`committer` is the ``on_iteration`` callback that commits every iteration.
"""

import fcntl
import io
import json
import logging
import os
import shutil
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from posefix.io.errors import InputError
from posefix.io.files import atomic_write_bytes
from posefix.spacetime.fit import resume_fit, start_fit, truncate_history

log = logging.getLogger(__name__)

_APPENDED_ROWS = ("order", "solver/H", "solver/Pi")     # grow along axis 0
_APPENDED_COLS = ("solver/G",)                          # grows along axis 1
_FIXED = ("solver/pi_p", "solver/phi_pp")               # set once


@contextmanager
def locked(folder):
    """Hold an advisory lock on the checkpoint ``folder`` (created) while the block runs; :class:`InputError`
    at once when another process holds it (two runs writing one results folder)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / "lock", "w") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise InputError(folder, "another fit is writing this checkpoint (two runs on one results folder?); "
                                     "let it finish or use another results folder") from None
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def remove(folder):
    """Remove the checkpoint ``folder`` (the fit is written; nothing is left to resume)."""
    shutil.rmtree(folder, ignore_errors=True)


def start_or_resume(points, values, settings, folder, key, device=None):
    """A fit continuing the checkpoint in ``folder`` where that is exact, else a fresh one.

    Parameters
    ----------
    points, values, settings, device
        As in :func:`posefix.spacetime.fit.start_fit`.
    folder : str or Path
    key : str
        Identifies the constraints and centre-selection parameters; a checkpoint of another key is ignored.

    Returns
    -------
    fit : posefix.spacetime.fit.GreedyFit
    resumed : int
        How many stored iterations it reuses (0: a fresh fit).
    """
    stored, history = load(folder, key)
    keep = truncate_history(history, settings) if stored is not None else 0
    if not keep:
        return start_fit(points, values, settings, device), 0
    log.info("resuming from checkpoint %s: %d of %d stored iterations (%d centres)", folder, keep, len(history),
             history[keep - 1]["centers"])
    return resume_fit(points, values, settings, stored, history[:keep], device), keep


def committer(folder, key, settings, fit, resumed):
    """The ``on_iteration`` callback of :func:`posefix.spacetime.fit.iterate` that commits every iteration.

    Stored iterations beyond the ``resumed`` ones (of a longer or different fit) are forgotten before
    the first new commit. ``settings`` (a dict) is recorded for information.
    """
    previous, first = (fit.state() if resumed else None), True

    def on_iteration(fit, record):
        nonlocal previous, first
        if first:
            truncate(folder, record["iteration"])
            first = False
        previous = save_iteration(folder, key, settings, fit, previous)

    return on_iteration


def save_iteration(folder, key, settings, fit, previous):
    """Commit the iteration just recorded in ``fit.history``.

    Parameters
    ----------
    folder : str or Path
    key : str
        Identifies the constraints and centre-selection parameters.
    settings : dict
        Recorded for information.
    fit : posefix.spacetime.fit.GreedyFit
    previous : dict or None
        ``state`` of the previous commit (for deltas); None for the first.

    Returns
    -------
    dict
        The state just committed (pass it as ``previous`` next time).
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    k = len(fit.history) - 1
    state = fit.state()
    delta = {}
    for name, value in state.items():
        if previous is not None and name in previous:
            if name in _APPENDED_ROWS:
                value = value[len(previous[name]):]
            elif name in _APPENDED_COLS:
                value = value[:, previous[name].shape[1]:]
            elif name in _FIXED or name.startswith(("solver/S/", "solver/L/")):
                continue
        delta[name] = value
    atomic_write_bytes(folder / f"iter-{k:05d}.npz", _npz_bytes(delta))
    meta = {"key": key, "settings": settings, "history": fit.history}
    atomic_write_bytes(folder / "meta.json", json.dumps(meta, indent=1).encode())
    return state


def load(folder, key):
    """The committed state and history of a checkpoint, or ``(None, [])`` if absent, of another key,
    or unreadable."""
    folder = Path(folder)
    try:
        meta = json.loads((folder / "meta.json").read_text())
        if meta.get("key") != key:
            return None, []
        history = meta["history"]
        state = {}
        for k in range(len(history)):
            with np.load(folder / f"iter-{k:05d}.npz") as delta:
                for name in delta.files:
                    value = delta[name]
                    if name in state and name in _APPENDED_ROWS:
                        state[name] = np.concatenate([state[name], value])
                    elif name in state and name in _APPENDED_COLS:
                        state[name] = np.concatenate([state[name], value], axis=1)
                    else:
                        state[name] = value
        return state, history
    except (OSError, ValueError, KeyError):
        return None, []


def truncate(folder, iterations):
    """Forget committed iterations from ``iterations`` on (their delta files)."""
    folder = Path(folder)
    for path in folder.glob("iter-*.npz"):
        if int(path.stem.split("-")[1]) >= iterations:
            os.unlink(path)


def _npz_bytes(arrays):
    buffer = io.BytesIO()
    np.savez(buffer, **{name: np.asarray(v) for name, v in arrays.items()})
    return buffer.getvalue()
