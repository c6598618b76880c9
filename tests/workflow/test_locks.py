"""Stale Snakemake locks are removed; those of a Snakemake still running in the folder are kept."""

import subprocess
import sys
import time
from pathlib import Path

import pytest

from posefix.workflow.locks import clear_stale_locks, snakemake_processes

pytestmark = pytest.mark.skipif(not Path("/proc/self").exists(), reason="needs /proc (Linux)")


def locked(folder):
    locks = folder / ".snakemake" / "locks"
    locks.mkdir(parents=True)
    for name in ("0.input.lock", "0.output.lock"):
        (locks / name).write_text("/some/file\n")
    return locks


def test_locks_of_no_running_snakemake_are_removed(tmp_path):
    locks = locked(tmp_path)
    assert clear_stale_locks(tmp_path) == [str(locks / "0.input.lock"), str(locks / "0.output.lock")]
    assert not any(locks.iterdir()) and clear_stale_locks(tmp_path) == []


def test_locks_of_a_running_snakemake_are_kept(tmp_path):
    locks = locked(tmp_path)
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)", "snakemake"], cwd=tmp_path)
    try:
        deadline = time.time() + 10
        while other.pid not in snakemake_processes(tmp_path) and time.time() < deadline:
            time.sleep(0.05)
        assert other.pid in snakemake_processes(tmp_path)
        assert clear_stale_locks(tmp_path) == [] and len(list(locks.iterdir())) == 2
    finally:
        other.kill()
        other.wait()
    assert len(clear_stale_locks(tmp_path)) == 2
