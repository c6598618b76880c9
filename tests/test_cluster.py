"""The demo library on a real SLURM cluster through profiles/slurm (issue 7).

A thread started with the session (``BackgroundRun``, from conftest's ``start_cluster``) starts
a one-node cluster on this machine (tests/cluster/slurm-up.sh: slurm-wlm and munge from apt,
controller and node on 127.0.0.1, no accounting daemon) and runs the demo through the profile while
the other tests run (the cluster tests are ordered last and join it); the session's teardown always
stops the cluster (tests/cluster/slurm-down.sh), also when a test fails. Needs root with apt-get (or slurm and
munge installed); skipped otherwise. Deselect with ``-m "not cluster"``.

The run uses the shipped workflow profile unchanged plus the command-line options of
``TEST_OPTIONS`` and ``_node_options``, which a cluster without slurmdbd on a small machine needs.
It repairs one of the demo's four poses, demo-04 (an .obj.gz: equal bytes need gzip without a time stamp;
``POSEFIX_CLUSTER_POSES``, "all" for the four), with S0 alone (the session's local demo run checks the other repairs
repairs): on 2 cores
every job pays about 7 s for SLURM and the two Snakemake processes it runs, and the plugin checks
for finished jobs i, i + (i + 10), ... seconds after its last status change (i: the first wait, 9 s
here: most jobs take 7-9 s), so the chain of 11 dependent stages takes 140-270 s. Started with the
session, it overlaps the other tests: `make test` on a fresh clone took 645.7 s with it (slurm-wlm and
munge installed by apt in 9 s, the cluster run 266 s in the background) and 716.7 s without it
(``-m "not cluster"``, right after, same clone: run-to-run noise is larger than what it adds).
"""

import json
import os
import re
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

import psutil
import pytest
import yaml

from conftest import ROOT, session_folder

pytestmark = [
    pytest.mark.cluster,
    pytest.mark.pipeline,
    # Checked before any fixture runs (the session's local demo run included).
    pytest.mark.skipif(os.geteuid() != 0, reason="the SLURM cluster test needs root (it installs "
                       "slurm-wlm/munge and starts their daemons)"),
    pytest.mark.skipif(shutil.which("sbatch") is None and shutil.which("apt-get") is None,
                       reason="SLURM is not installed and there is no apt-get to install slurm-wlm and munge"),
]

CLUSTER = ROOT / "tests" / "cluster"
PROFILE = ROOT / "profiles" / "slurm"
LOCALRULES = {"all", "summary", "overview"}  # the Snakefile's localrules: never submitted
RUN_TIMEOUT = 600  # seconds for the whole run on the cluster (measured: 138-196 s on 2 cores)
POSES = os.environ.get("POSEFIX_CLUSTER_POSES", "demo-04")

TEST_OPTIONS = [
    # No slurmdbd: sacct cannot answer; squeue can while finished jobs stay MinJobAge (300 s) listed.
    "--slurm-status-command", "squeue",
    "--slurm-init-seconds-before-status-checks", "9",  # first check after 9 s (default 40): most jobs take 7-9 s
    "--slurm-no-account",  # no accounts on this cluster (plugin 2.8 still guesses, fails, goes on)
    "--slurm-keep-successful-logs",  # .snakemake/slurm_logs/ of every job, as evidence
    "--retries", "0",  # a failure fails the test instead of being retried
    "--jobs", "8",
]


def _run(cmd, timeout, **kwargs):
    """subprocess.run under coreutils' timeout (TERM, then KILL 10 s later), output captured."""
    return subprocess.run(["timeout", "-k", "10", str(timeout), *map(str, cmd)], capture_output=True,
                          text=True, **kwargs)


def _node_options(env):
    """Threads as in config.yaml (the local run's, so results can be compared byte for byte, and no
    more than the node's CPUs: SLURM leaves larger jobs pending forever) and the profile's memory
    capped to half the node's."""
    node = subprocess.run(["scontrol", "-o", "show", "node"], capture_output=True, text=True, env=env,
                          check=True).stdout
    cpus = int(re.search(r"\bCPUTot=(\d+)", node).group(1))
    memory = int(re.search(r"\bRealMemory=(\d+)", node).group(1))
    config = yaml.safe_load((ROOT / "config.yaml").read_text())
    profile = yaml.safe_load((PROFILE / "config.yaml").read_text())
    threads = [f"{rule}={min(config[rule]['threads'], cpus)}" for rule in profile["set-threads"]]
    resources = []
    for rule, values in profile["set-resources"].items():
        for name, value in values.items():
            if name == "mem_mb":
                value = min(int(value), memory // 2)
            resources.append(f"{rule}:{name}={value}")
    return ["--set-threads", *threads, "--set-resources", *resources]


class _QueueWatch(threading.Thread):
    """Polls squeue every second while the workflow runs: jobid -> (name, comment, last state)."""

    def __init__(self, env):
        super().__init__(daemon=True)
        self.env, self.jobs, self.stop = env, {}, threading.Event()

    def poll(self):
        out = subprocess.run(["squeue", "--states=all", "-h", "-o", "%i|%j|%k|%T"], capture_output=True,
                             text=True, env=self.env).stdout
        for line in out.splitlines():
            jobid, name, comment, state = line.split("|", 3)
            self.jobs[jobid] = (name, comment, state)

    def run(self):
        while not self.stop.wait(1.0):
            self.poll()


def _job_stats(text):
    """Snakemake's "Job stats" table of a run: rule -> number of jobs."""
    table = text.split("Job stats:", 1)[1].split("total", 1)[0]
    return {m.group(1): int(m.group(2)) for m in re.finditer(r"^(\w+)\s+(\d+)\s*$", table, re.M)}


def _rule_of(comment):
    """The rule of a job from the comment the plugin gives it: rule_<rule>[_wildcards_...]."""
    return re.match(r"rule_(.+?)(?:_wildcards_.*)?$", comment).group(1)


def _without_timing(value):
    """summary.json without the wall-clock fields (every key containing "seconds")."""
    if isinstance(value, dict):
        return {k: _without_timing(v) for k, v in value.items() if "seconds" not in k}
    if isinstance(value, list):
        return [_without_timing(v) for v in value]
    return value


class BackgroundRun(threading.Thread):
    """The cluster part, in a thread from the session's start (conftest's ``start_cluster``, in the
    xdist controller when there are workers): start the one-node cluster (slurm-up.sh: apt-get when
    needed), then run the demo through the workflow profile. It waits mostly on SLURM and Snakemake's
    status checks, so it overlaps the rest of the suite. When done it writes ``report``, a JSON object
    that the tests of this module, ordered last, wait for (:func:`cluster_run`): ``skip`` (why the
    cluster cannot run here) or ``error`` or ``result`` = [work folder, exit status, log text, SLURM
    jobs of the run]; ``messages``: the scripts' output and the timings. ``stop`` always runs
    slurm-down.sh (the session's end, also after a failure or an interrupt).
    """

    def __init__(self, state, work, report):
        super().__init__(daemon=True)
        self.state, self.work, self.report = state, work, report
        self.env = {**os.environ, "SLURM_CONF": str(state / "slurm.conf")}
        self.skip = self.error = self.result = None
        self.log = []

    def run(self):
        try:
            self._run()
        finally:
            partial = self.report.with_suffix(".part")
            partial.write_text(json.dumps({"skip": self.skip, "error": self.error, "result": self.result,
                                           "messages": self.log}))
            partial.replace(self.report)

    def _run(self):
        try:
            start = time.monotonic()
            up = _run([CLUSTER / "slurm-up.sh", self.state], 600, env=self.env)
            self.log += [up.stdout, up.stderr, f"slurm-up.sh: exit {up.returncode} after "
                                               f"{time.monotonic() - start:.0f} s"]
            if up.returncode == 3:
                self.skip = (up.stderr.strip().splitlines() or ["slurm-up.sh exited 3"])[-1]
            elif up.returncode != 0:
                self.error = f"slurm-up.sh failed ({up.returncode})"
            else:
                self.result = self._workflow()
        except Exception as exc:  # reported by the tests, not lost in the thread
            self.error = repr(exc)

    def _workflow(self):
        cmd = [sys.executable, "-m", "snakemake", "-s", ROOT / "Snakefile", "--directory", self.work,
               "--workflow-profile", PROFILE, *TEST_OPTIONS, *_node_options(self.env)]
        cmd = cmd + ["--config", "repairs=[]"] + ([f"poses={POSES}"] if POSES != "all" else [])
        watch = _QueueWatch(self.env)
        watch.start()
        start = time.monotonic()
        try:
            proc = _run(cmd, RUN_TIMEOUT, env=self.env)
        finally:
            watch.stop.set()
            watch.join()
        seconds = time.monotonic() - start
        watch.poll()  # finished jobs stay listed for MinJobAge (300 s)
        log = proc.stdout + proc.stderr
        (self.work / "snakemake.log").write_text(log)
        run_id = re.search(r"SLURM run ID: (\S+)", log)
        jobs = {j: v for j, v in watch.jobs.items() if run_id and v[0] == run_id.group(1)}
        table = "\n".join(f"{j:>6} {_rule_of(c):<12} {c:<40} {s}" for j, (_, c, s) in
                          sorted(jobs.items(), key=lambda kv: int(kv[0])))
        (self.work / "slurm-jobs.txt").write_text(table + "\n")
        self.log.append(f"cluster run: exit {proc.returncode} after {seconds:.0f} s in {self.work}; "
                        f"SLURM jobs:\n{table}")
        return str(self.work), proc.returncode, log, jobs

    def stop(self, wait=True):
        """Stop the cluster, after the run when ``wait`` (it is bounded by its timeouts), else at once with the run
        (an interrupted session)."""
        if wait:
            self.join(timeout=600 + RUN_TIMEOUT + 60)
        else:  # coreutils' timeout passes TERM on to the workflow, which cancels its jobs, and KILLs it 10 s later
            runs = [child for child in psutil.Process().children() if str(self.work) in " ".join(child.cmdline())]
            for child in runs:
                child.terminate()
            psutil.wait_procs(runs, timeout=30)  # the controller still up, so that the jobs can be cancelled
        down = _run([CLUSTER / "slurm-down.sh", self.state], 120, env=self.env)
        print(down.stdout, down.stderr, sep="")


def reason_not_runnable_here():
    """Why the cluster part cannot run on this machine (the module's skip reasons), or None."""
    for mark in pytestmark:
        if mark.name == "skipif" and mark.args[0]:
            return mark.kwargs["reason"]
    return None


@pytest.fixture(scope="module")
def cluster_run(tmp_path_factory, request):
    """The session's background run, finished (its report, :class:`BackgroundRun`): (its folder, its exit
    status, its output, the SLURM jobs of the run, the local run's folder: the session's demo_run)."""
    report = session_folder(tmp_path_factory) / "cluster.json"
    deadline = time.monotonic() + 600 + RUN_TIMEOUT + 60
    while not report.exists():
        if time.monotonic() > deadline:
            pytest.fail(f"the session's SLURM run wrote no {report}")
        time.sleep(2.0)
    run = json.loads(report.read_text())
    print("\n".join(run["messages"]))
    if run["skip"]:
        pytest.skip(f"cannot start a SLURM cluster here: {run['skip']}")
    assert run["error"] is None, run["error"]
    work, returncode, log, jobs = run["result"]
    return Path(work), returncode, log, jobs, request.getfixturevalue("demo_run")


def test_demo_runs_on_slurm_with_the_workflow_profile(cluster_run):
    work, returncode, log, jobs, _ = cluster_run
    assert returncode == 0, f"snakemake exited {returncode} (124/137: timed out):\n{log[-4000:]}"
    assert (work / "reports" / "demo" / "summary.json").exists()
    assert (work / "reports" / "demo" / "overview.png").exists()


def test_every_rule_but_the_local_ones_ran_as_a_slurm_job(cluster_run):
    work, returncode, log, jobs, _ = cluster_run
    assert returncode == 0, log[-4000:]
    stats = _job_stats(log)
    assert LOCALRULES <= set(stats) and stats["fit"] == len(_poses(work)), stats
    # 1. The plugin's own account of it: one "submitted with SLURM jobid" line per non-local job.
    submitted = re.findall(r"Job \d+ has been submitted with SLURM jobid (\d+) \(log: (\S+)\)", log)
    assert len(submitted) == sum(n for rule, n in stats.items() if rule not in LOCALRULES)
    # 2. SLURM's: squeue lists every one of them with its rule in the comment, COMPLETED.
    expected = {rule: n for rule, n in stats.items() if rule not in LOCALRULES}
    per_rule = {}
    for jobid, _ in submitted:
        assert jobid in jobs, f"SLURM job {jobid} never seen by squeue"
        _, comment, state = jobs[jobid]
        assert state == "COMPLETED", (jobid, comment, state)
        per_rule[_rule_of(comment)] = per_rule.get(_rule_of(comment), 0) + 1
    assert per_rule == expected
    # 3. The job logs under .snakemake/slurm_logs/rule_<rule>/, one per job.
    logs = {rule: len(list((work / ".snakemake" / "slurm_logs" / f"rule_{rule}").rglob("*.log")))
            for rule in stats}
    assert logs == {rule: expected.get(rule, 0) for rule in stats}
    # The local rules ran in the submitting process.
    for rule in LOCALRULES:
        assert re.search(rf"^localrule {rule}:", log, re.M), rule


def _poses(work):
    """The poses the run repaired (from its summary)."""
    summary = json.loads((work / "reports" / "demo" / "summary.json").read_text())
    return [e["pose"] for e in summary["poses"]]


def test_cluster_results_equal_the_local_run(cluster_run):
    """The local run repaired all four poses; the poses of the cluster run are the same bytes and
    numbers (a pose's stages do not depend on the other poses), the other repairs aside (S0 alone here)."""
    work, returncode, log, jobs, demo_run = cluster_run
    assert returncode == 0, log[-4000:]
    poses = _poses(work)
    assert poses and (POSES == "all" or poses == POSES.split(","))
    local, remote = demo_run / "results" / "demo" / "repaired", work / "results" / "demo" / "repaired"
    names = sorted(p.name for p in local.iterdir() if p.name.split(".")[0] in poses)
    assert len(names) == len(poses) and names == sorted(p.name for p in remote.iterdir())
    for name in names:  # byte for byte (the stages are deterministic, gzip without a time stamp)
        assert (local / name).read_bytes() == (remote / name).read_bytes(), name
    a, b = (json.loads((run / "reports" / "demo" / "summary.json").read_text()) for run in (demo_run, work))
    assert a["library"] == b["library"]
    entries = {e["pose"]: {k: v for k, v in _without_timing(e).items() if k != "repairs"} for e in a["poses"]}
    assert [_without_timing(e) for e in b["poses"]] == [entries[p] for p in poses]
