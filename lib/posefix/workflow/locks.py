"""Stale Snakemake locks: left by a run that was killed, they make the next run refuse to start.

Snakemake locks a working directory with files in ``.snakemake/locks/`` and removes them when it ends; a
``kill -9`` (or a closed terminal, a machine that went down) leaves them, and the same command then stops
with ``LockException`` until ``snakemake --unlock``. They are stale when no other Snakemake process on this
machine runs in the same directory: then they are removed. Linux only (``/proc``); elsewhere nothing is
removed and :func:`clear_stale_locks` says so.
"""

import logging
import os
from pathlib import Path

log = logging.getLogger(__name__)


def snakemake_processes(directory, proc="/proc"):
    """PIDs of the processes on this machine, other than this one and its ancestors, whose command line
    mentions snakemake and whose working directory is ``directory``, (list of int)."""
    directory = os.path.realpath(directory)
    own = set(_ancestors(proc))
    found = []
    for entry in Path(proc).iterdir():
        if not entry.name.isdigit() or int(entry.name) in own:
            continue
        try:
            cmdline = (entry / "cmdline").read_bytes()
            cwd = os.path.realpath(os.readlink(entry / "cwd"))
        except OSError:  # gone, or not ours to read
            continue
        if b"snakemake" in cmdline and cwd == directory:
            found.append(int(entry.name))
    return found


def _ancestors(proc):
    """This process and its ancestors (PIDs)."""
    pid, chain = os.getpid(), []
    while pid > 0 and pid not in chain:
        chain.append(pid)
        try:
            stat = (Path(proc) / str(pid) / "stat").read_text()
        except OSError:
            break
        pid = int(stat.rsplit(")", 1)[1].split()[1])  # field 4, after the command name in parentheses
    return chain


def clear_stale_locks(directory=".", proc="/proc"):
    """Remove ``directory/.snakemake/locks/*`` when no other Snakemake runs in ``directory``.

    Returns
    -------
    list of str
        The lock files removed (empty when there were none, another Snakemake runs there, or there is
        no ``/proc`` to tell).
    """
    locks = sorted((Path(directory) / ".snakemake" / "locks").glob("*.lock"))
    if not locks:
        return []
    if not Path(proc, str(os.getpid())).exists():
        log.warning("Snakemake locks in %s and no /proc to tell whether they are stale: if no run is going on "
                    "there, `snakemake --unlock` clears them", directory)
        return []
    if snakemake_processes(directory, proc):
        return []
    for lock in locks:
        lock.unlink(missing_ok=True)
    return [str(lock) for lock in locks]
