"""Crash-safe checkpoints of a greedy fit (file I/O).

A checkpoint is a folder next to the fit's output::

    fit.checkpoint/meta.json          key, settings, history (one record per committed iteration)
    fit.checkpoint/iter-00000.npz     what iteration 0 added: centre indices, factor block, ...
    fit.checkpoint/iter-00001.npz     ...

Every file is written to a temporary name and renamed; ``meta.json`` is rewritten last, so it is
the commit record: a kill at any moment leaves either the previous or the new iteration
committed, never a half-written one. Everything the fit's state holds is append-only
(:meth:`posefix.spacetime.fit.GreedyFit.state`), so each iteration stores only its delta.
"""

import io
import json
import os
from pathlib import Path

import numpy as np

from posefix.pipeline.files import atomic_write_bytes

_APPENDED_ROWS = ("order", "solver/H", "solver/Pi")     # grow along axis 0
_APPENDED_COLS = ("solver/G",)                          # grows along axis 1
_FIXED = ("solver/pi_p", "solver/phi_pp")               # set once


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
