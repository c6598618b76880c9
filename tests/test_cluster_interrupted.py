"""A cluster test killed with SIGTERM leaves no SLURM daemon and no job running (issue 50).

The test runs the cluster test (tests/test_cluster.py) in a nested pytest with a second one-node cluster beside the
session's own: other ports and state folder, and /etc/slurm/slurm.conf left alone (``POSEFIX_SLURM_ETC_LINK=0``).
Once its workflow has a job on that cluster, it sends the nested pytest SIGTERM, as a CI runner or ``kill`` would.
conftest's ``start_cluster`` turns the signal into an interrupt, and ``pytest_sessionfinish`` then stops the
workflow and runs slurm-down.sh. This module's name does not select the session's own SLURM run (conftest starts it
for tests/test_cluster.py only); in the full suite it runs last, after that run, whose munged it then shares.
"""

import contextlib
import os
import signal
import subprocess
import sys
import time

import psutil
import pytest

from conftest import ROOT
from test_cluster import CLUSTER, pytestmark  # noqa: F401 (the same marks and skip reasons)

PORTS = {"POSEFIX_SLURMCTLD_PORT": "6837", "POSEFIX_SLURMD_PORT": "6838"}  # the session's cluster has 6817/6818
STARTED_TIMEOUT = 300  # seconds until the nested run has a SLURM job (slurm-up.sh, Snakemake's start)
STOPPED_TIMEOUT = 60  # seconds for the interrupted pytest to stop the workflow and the cluster


def _nested_env():
    """This environment without pytest-xdist's worker variables (the nested pytest is one process of its own)."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST_XDIST") and k != "SLURM_CONF"}
    return {**env, **PORTS, "POSEFIX_SLURM_ETC_LINK": "0"}


def _has_a_job(state):
    """Whether the cluster of ``state`` (slurm-up.sh's state folder) lists a job."""
    if not (state / "slurm.conf").exists():
        return False
    queue = subprocess.run(["squeue", "-h", "-o", "%i"], capture_output=True, text=True, timeout=30,
                           env={**os.environ, "SLURM_CONF": str(state / "slurm.conf")})
    return queue.returncode == 0 and bool(queue.stdout.strip())


def _processes_of(state, work):
    """The cluster's daemons (by their pid files) and every process that runs in or names the run's folder."""
    found = {int((state / f"{name}.pid").read_text()) for name in ("slurmctld", "slurmd")
             if (state / f"{name}.pid").exists()}
    for proc in psutil.process_iter(["pid", "cmdline", "cwd"]):
        if str(work) in " ".join(proc.info["cmdline"] or []) or str(work) in (proc.info["cwd"] or ""):
            found.add(proc.info["pid"])
    return found


def _alive(pids):
    """The pids of ``pids`` that still run (zombies count as gone)."""
    alive = []
    for pid in pids:
        try:
            if psutil.Process(pid).status() != psutil.STATUS_ZOMBIE:
                alive.append(pid)
        except psutil.NoSuchProcess:
            pass
    return alive


def test_a_cluster_test_killed_with_sigterm_leaves_no_daemon_or_job(tmp_path):
    base = tmp_path / "nested"
    state, work = base / "slurm", base / "cluster-run"
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--basetemp", str(base),
           "tests/test_cluster.py::test_demo_runs_on_slurm_with_the_workflow_profile"]
    nested = subprocess.Popen(cmd, cwd=ROOT, env=_nested_env(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + STARTED_TIMEOUT
        while not _has_a_job(state):
            assert nested.poll() is None, f"the nested cluster test ended early:\n{nested.stdout.read()[-3000:]}"
            assert time.monotonic() < deadline, f"no SLURM job on the nested cluster after {STARTED_TIMEOUT} s"
            time.sleep(1.0)
        running = _processes_of(state, work)
        nested.send_signal(signal.SIGTERM)
        output, _ = nested.communicate(timeout=STOPPED_TIMEOUT)
        time.sleep(2.0)
        left = _alive(running)
        assert not left, f"still running after SIGTERM: {left}\n{output[-3000:]}"
        assert nested.returncode == pytest.ExitCode.INTERRUPTED, output[-3000:]
        assert "slurm-down: stopping slurmctld" in output and not (state / "slurmctld.pid").exists(), output[-3000:]
    finally:
        if nested.poll() is None:
            os.killpg(nested.pid, signal.SIGKILL)
        subprocess.run([CLUSTER / "slurm-down.sh", state], capture_output=True, timeout=120)
        for pid in _alive(_processes_of(state, work)):  # a failed test leaves no orphan either
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
