"""The repair as a background process: a pose job (``python -m posefix.workflow.pose_job``) in the posefix
environment, started from Blender, read back line by line, and stopped on cancel (no Blender interface here)."""

import json
import os
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

PYTHON_VARIABLE = "POSEFIX_PYTHON"
"""The environment variable naming the posefix environment's Python, when the preferences leave it empty."""


def posefix_python(preferred=""):
    """The Python of the posefix environment (str): ``preferred`` (the add-on's preference), else
    ``$POSEFIX_PYTHON``, else the interpreter of the ``posefix`` command on the PATH; None where there is none."""
    for candidate in (preferred, os.environ.get(PYTHON_VARIABLE, "")):
        if candidate:
            return candidate
    command = shutil.which("posefix")
    if command:
        first = Path(command).read_text(errors="replace").splitlines()[:1]
        if first and first[0].startswith("#!"):
            return first[0][2:].strip().split()[0]
    return None


class Job:
    """A running pose job: its folder, its process and the lines it has written (one JSON line a finished pose).

    Parameters
    ----------
    python : str
        The posefix environment's Python.
    arrays : dict
        The job's arrays (:func:`shape_keys.job_arrays`).
    cores : int
        Poses repaired at once.
    """

    def __init__(self, python, arrays, cores=2):
        self.folder = Path(tempfile.mkdtemp(prefix="posefix-shape-keys-"))
        np.savez(self.folder / "job.npz", **arrays)
        self.total, self.lines, self.errors = len(arrays["names"]), [], []
        self.process = subprocess.Popen([python, "-m", "posefix.workflow.pose_job", str(self.folder), "--cores",
                                         str(cores)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                        start_new_session=True)
        self._readers = [threading.Thread(target=self._read, args=(stream, sink), daemon=True)
                         for stream, sink in ((self.process.stdout, self.lines), (self.process.stderr, self.errors))]
        for reader in self._readers:
            reader.start()

    @staticmethod
    def _read(stream, sink):
        for line in stream:
            sink.append(line.rstrip("\n"))

    def done(self):
        """Whether the process has ended (its output read)."""
        if self.process.poll() is None:
            return False
        for reader in self._readers:
            reader.join()
        return True

    def finished(self):
        """The poses finished so far: the job's lines (dicts)."""
        return [json.loads(line) for line in self.lines if line.startswith("{")]

    def failure(self):
        """Why the job failed, one line (str), or None when it ended well (call once :meth:`done`)."""
        if self.process.returncode == 0:
            return None
        said = [line for line in self.errors if line.startswith("posefix: error:")]
        return said[0] if said else (self.errors[-1] if self.errors else f"the job ended with {self.process.returncode}")

    def repaired(self, index):
        """The repaired positions of pose ``index``, (n, 3) float64."""
        return np.load(self.folder / f"repaired-{index}.npy")

    def cancel(self):
        """Stop the job and its workers (the process group)."""
        if self.process.poll() is None:
            os.killpg(self.process.pid, signal.SIGTERM)
            self.process.wait()

    def close(self):
        """Remove the job's folder."""
        shutil.rmtree(self.folder, ignore_errors=True)


def wait(job, on_line=None, poll=0.1):
    """Wait for ``job`` to end, calling ``on_line(finished lines)`` as poses finish; ``job.failure()``."""
    seen = 0
    while not job.done():
        time.sleep(poll)
        if on_line and len(job.lines) > seen:
            seen = len(job.lines)
            on_line(job.finished())
    if on_line:
        on_line(job.finished())
    return job.failure()

