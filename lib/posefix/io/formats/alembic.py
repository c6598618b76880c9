"""Alembic caches (``.abc``): a mesh's frames, one pose a frame, read and written by Blender's Alembic importer and
exporter. posefix runs Blender in a process of its own (:func:`blender_command`: a Python with bpy 4.5, or Blender
itself) with ``alembic_blender.py``, because bpy cannot share posefix's environment (it pins numpy < 2).

Frames are named as USD's, ``<file stem>-<frame>`` (``anim-012``). An Alembic cache has no rest pose: the reference
is a frame (``reference=1``; default the first). The file written back (:meth:`AlembicContainer.write`) is Blender's
export of the imported cache: the same objects, names and frame range, the chosen mesh's points replaced in the
repaired frames (float32, as Alembic stores them).
"""

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from posefix.io.containers import Container, container_stem, fan_triangles, frame_labels, pose_names
from posefix.io.errors import InputError
from posefix.io.files import atomic_path

BLENDER_VARIABLE = "POSEFIX_BLENDER"
"""The environment variable naming the Python with bpy (or the Blender executable) that reads and writes Alembic."""

SCRIPT = Path(__file__).with_name("alembic_blender.py")
ERROR = "posefix-alembic: error: "


class AlembicContainer(Container):
    """An Alembic mesh and its frames (:class:`posefix.io.containers.Container`); ``details``: ``frames`` (list of
    float) and their ``points`` (k, n, 3) float64."""

    def where(self, name):
        return f"mesh {self.mesh}, frame {self.members[name]:g}"

    def values(self, name):
        return self.details["points"][self.details["frames"].index(self.members[name])]

    def write(self, out, positions):
        points = self.details["points"].copy()
        for name, X in positions.items():
            points[self.details["frames"].index(self.members[name])] = X
        with tempfile.TemporaryDirectory() as scratch, atomic_path(out) as tmp:
            job = os.path.join(scratch, "job.npz")
            np.savez(job, mesh=self.mesh, frames=np.array(self.details["frames"], dtype=np.int64), points=points)
            written = os.path.join(scratch, "out.abc")
            run_blender(self.path, "write", self.path, written, job)
            os.replace(written, tmp)


def open_container(path, mesh=None):
    """The :class:`AlembicContainer` of the mesh ``mesh`` (an object name; None: the only mesh) of ``path``."""
    with tempfile.TemporaryDirectory() as scratch:
        out = os.path.join(scratch, "read.npz")
        run_blender(path, "read", path, out, mesh or "")
        with np.load(out) as data:
            name, frames, points = str(data["mesh"]), [float(f) for f in data["frames"]], data["points"]
            counts, indices = data["counts"], data["indices"]
    n = points.shape[1]
    faces = fan_triangles(f"{path} (mesh {name})", counts, indices, n)
    if not len(faces):
        raise InputError(path, f"mesh {name} has no faces")
    members = dict(zip(pose_names(path, frame_labels(container_stem(path), frames)), frames))
    return AlembicContainer(path=path, mesh=name, members=members, rest=None, faces=faces, n=n, rebase=True,
                            details={"frames": frames, "points": points.astype(np.float64)})


def blender_command(path):
    """The command (list of str) that runs ``alembic_blender.py``: ``$POSEFIX_BLENDER`` (a Python with bpy, or a
    Blender executable), else ``blender`` on the PATH; InputError naming what to install where there is none."""
    chosen = os.environ.get(BLENDER_VARIABLE) or shutil.which("blender")
    if not chosen:
        raise InputError(path, "Alembic caches are read and written by Blender: install Blender 4.2 or later (the "
                               "blender command), or bpy 4.5 in a Python 3.11 environment of its own (make "
                               f".venv-blender), and name it in ${BLENDER_VARIABLE}")
    if "python" in Path(chosen).name:
        return [chosen, str(SCRIPT)]
    return [chosen, "--background", "--factory-startup", "--python-exit-code", "2", "--python", str(SCRIPT), "--"]


def run_blender(path, *args):
    """Run ``alembic_blender.py`` with ``args``; its one-line error (or Blender's failure) as InputError on
    ``path``."""
    proc = subprocess.run(blender_command(path) + [str(a) for a in args], capture_output=True, text=True)
    said = [line[len(ERROR):] for line in proc.stderr.splitlines() if line.startswith(ERROR)]
    if said:
        raise InputError(path, said[-1])
    if proc.returncode != 0:  # Blender itself stopped (a C++ exception of the Alembic library)
        last = [line.strip().removeprefix("what():").strip() for line in proc.stderr.splitlines() if line.strip()]
        detail = (last[-1] if last else f"exit status {proc.returncode}")[:200]
        raise InputError(path, f"cannot be read as Alembic: Blender stopped on it ({detail}); a damaged or truncated "
                               "file?" if args[0] == "read" else f"Blender stopped writing it ({detail})")
