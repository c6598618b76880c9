"""Shared fixtures: paths, the shared pose libraries (skipped when absent), small meshes, stage runner."""

import fcntl
import io
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh
from threadpoolctl import threadpool_limits

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSEFIX_DATA", ROOT.parent / "shared" / "data"))


def shared_library(name):
    """Path of a pose library in ../shared/data, or skip the test with the reason."""
    path = DATA / name
    if not path.is_dir():
        pytest.skip(f"needs the shared pose library {path} (../shared/data is absent)")
    return path


def icosphere(subdivisions=2, radius=1.0, centre=(0.0, 0.0, 0.0)):
    """A closed, clean sphere mesh: (V (n, 3) float, F (m, 3) int64)."""
    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return np.asarray(m.vertices) + np.asarray(centre), np.asarray(m.faces, dtype=np.int64)


def split_along_a_seam(V, F):
    """Split the vertices used by faces on both sides of the plane x = 0 (a copy appended, used by the faces
    with x < 0), as an exporter does along a UV seam: (faces (m, 3) on the n + s vertices ``V ++ V[originals]``,
    originals (s,), copies (s,))."""
    left = V[F].mean(axis=1)[:, 0] < 0
    shared = np.intersect1d(F[left], F[~left])
    copies = len(V) + np.arange(len(shared))
    remap = np.arange(len(V))
    remap[shared] = copies
    F2 = F.copy()
    F2[left] = remap[F[left]]
    return F2, shared, copies


def grid_sheet(n, z):
    """An n x n grid of the unit square at height z: (n*n, 3) float vertices, (2(n-1)^2, 3) int64 faces."""
    g = np.linspace(0, 1, n)
    V = np.column_stack([np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2), np.full(n * n, z)])
    F = [[i * n + j, (i + 1) * n + j, (i + 1) * n + j + 1] for i in range(n - 1) for j in range(n - 1)]
    F += [[i * n + j, (i + 1) * n + j + 1, i * n + j + 1] for i in range(n - 1) for j in range(n - 1)]
    return V, np.array(F, dtype=np.int64)


def smooth_field_problem(n=2000, seed=0):
    """Space-time constraints of a smooth field: points (n, 4) in the unit box, values (n, 3)."""
    rng = np.random.default_rng(seed)
    Y = rng.uniform(0, 1, size=(n, 4))
    V = np.stack([np.sin(Y @ [1.0, 0.5, 0.3, 0.2]), np.cos(Y @ [0.2, 0.7, 0.4, 0.1]), 0.2 * (Y ** 3).sum(1)], 1)
    return Y, V


def float32_crossing():
    """Two triangles whose faces intersect once their positions are rounded to float32: ``(V_ref, X, F)``, the
    reference (apart) and the pose (triangle B's corner 2e-8 above triangle A, coordinates about 1: their float32
    spacing is 1.2e-7), (6, 3) float64 each, and F (2, 3). A is float32-exact."""
    normal = np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0)
    A = np.array([[0.5, -1.0, 1.5], [1.5, -1.0, 0.5], [1.0, 1.0, 1.0]])  # in the plane x + z = 2
    corner = np.array([1.07744149870135782, 0.1, 0.92255850129864218]) + 2e-8 * normal
    B = np.array([corner, corner + [0.3, 0.3, 0.3] + 0.3 * normal, corner + [-0.3, 0.3, 0.3] + 0.5 * normal])
    return np.vstack([A, B + 0.5 * normal]), np.vstack([A, B]), np.array([[0, 1, 2], [3, 4, 5]])


def pixels(fig):
    """The RGB pixels (h, w, 3) of a matplotlib figure drawn as PNG."""
    from matplotlib.image import imread
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return imread(io.BytesIO(buffer.getvalue()))[..., :3]


def run_stage(name, *args, check=True):
    """Run ``stages/<name>.py`` with this interpreter; returns the CompletedProcess."""
    proc = subprocess.run([sys.executable, str(ROOT / "stages" / f"{name}.py"), *map(str, args)],
                          capture_output=True, text=True, cwd=ROOT)
    if check and proc.returncode != 0:
        raise AssertionError(f"stage {name} failed ({proc.returncode}):\n{proc.stderr}")
    return proc


def snakemake(workdir, *args):
    """Run the workflow with this interpreter's snakemake in ``workdir`` (one downstream setting, as
    the session's demo run); returns the CompletedProcess."""
    cmd = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--directory", str(workdir),
           "--cores", "2", *map(str, args)]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=900)


def h5_datasets(path):
    """Every dataset of the HDF5 file ``path``: {name: value}."""
    import h5py
    out = {}
    with h5py.File(path, "r") as fh:
        fh.visititems(lambda n, o: out.__setitem__(n, o[()]) if isinstance(o, h5py.Dataset) else None)
    return out


def session_folder(tmp_path_factory):
    """The session's base temporary folder, shared by pytest-xdist's workers (`make test` runs on ``CORES``
    processes): each worker's own is a subfolder of it."""
    base = tmp_path_factory.getbasetemp()
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


def once_per_session(tmp_path_factory, name, make):
    """The folder ``name`` in :func:`session_folder`, made by ``make(folder)`` once per session: the first worker
    to ask makes it, holding a lock; the others wait and share it (read-only). A failed ``make`` is tried again by
    the next to ask."""
    base = session_folder(tmp_path_factory)
    folder, done = base / name, base / f"{name}.done"
    with open(base / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not done.exists():
            folder.mkdir(exist_ok=True)
            make(folder)
            done.touch()
    return folder


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory):
    """The workflow on the demo library, run locally (``snakemake --cores 2``) once per session: the
    folder it ran in. Read-only for its users (test_workflow, and test_cluster's reference run)."""
    def make(work):
        cmd = [sys.executable, "-m", "snakemake", "-s", str(ROOT / "Snakefile"), "--directory", str(work),
               "--cores", "2"]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
        assert proc.returncode == 0, proc.stderr[-3000:]
    return once_per_session(tmp_path_factory, "demo-run", make)


LION_POSES = ("lion-04",)
"""The lion pose the session's lion run repairs: one of the three with an independent target count (SOURCES.md),
the one with the most (717 faces), to keep CI short (every pose, and the library as USD and GLB files: make
bench)."""


@pytest.fixture(scope="session")
def lion_run(tmp_path_factory):
    """The workflow on :data:`LION_POSES` of ../shared/data/lion-poses with S0 alone (``repairs=[]``; every pose
    and every repair: make bench) and one downstream step up to the library's summary (no figures, no viewer), once
    per session: the folder it ran in (skips when the library is absent)."""
    library = shared_library("lion-poses")

    def make(work):
        proc = snakemake(work, "reports/lion-poses/summary.json", "--config", f"library={library}", "repairs=[]",
                         f"poses={','.join(LION_POSES)}", "downstream={'max_iters': 1}")
        assert proc.returncode == 0, proc.stderr[-3000:]
    return once_per_session(tmp_path_factory, "lion-run", make)


@pytest.fixture(scope="session")
def demo():
    """The demo library in memory: (V_ref, F, poses dict)."""
    from posefix.workflow.demo import demo_library
    return demo_library()


# OpenBLAS threads made small dense operations up to 17x slower on the 2-core CI machines
# (measured on the greedy fit); the stages cap BLAS to their rule's threads, the tests to one.
threadpool_limits(1)


LONGEST_FIRST = ("test_workflow.py", "test_lion_library.py", "test_container_libraries.py",
                 "test_authoring_workflow.py", "test_recovery.py", "workflow/test_command.py", "test_stages.py")
"""The end-to-end test files (paths under tests/), longest first: `make test` hands files to its processes in
collection order (``--dist loadfile --no-loadscope-reorder``), so these start first and the unit tests fill in
around them. The first two make the session's demo run and lion run, which later files share."""


def pytest_collection_modifyitems(session, config, items):
    """:data:`LONGEST_FIRST`, then the other files in their order, the cluster tests last: they wait for the
    session's SLURM run (:func:`start_cluster`)."""
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}

    def key(item):
        name = Path(item.path).relative_to(ROOT / "tests").as_posix()
        return item.get_closest_marker("cluster") is not None, rank.get(name, len(rank))
    items.sort(key=key)


def pytest_collection_finish(session):
    """One process (no xdist): start the SLURM run once the selected tests are known."""
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        start_cluster(session.config, [item.nodeid for item in session.items])


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_node_collection_finished(node, ids):
    """xdist's controller, as each worker reports the selected tests: start the SLURM run (once)."""
    start_cluster(node.config, ids)


def start_cluster(config, ids):
    """Start test_cluster.BackgroundRun in this process (the controller under xdist) when the tests ``ids`` include
    the cluster tests and they can run here. It runs from the session's start, mostly waiting on SLURM, so it
    overlaps everything else; it writes ``cluster.json`` into :func:`session_folder`, which the cluster tests
    wait for, in whichever worker they run; :func:`pytest_sessionfinish` shuts the cluster down."""
    if config.option.collectonly or getattr(config, "posefix_cluster", None) \
            or not any("test_cluster.py::" in i for i in ids):
        return
    import test_cluster
    if test_cluster.reason_not_runnable_here():
        return
    base = config._tmp_path_factory.getbasetemp()
    for folder in ("slurm", "cluster-run"):
        (base / folder).mkdir()
    config.posefix_cluster = test_cluster.BackgroundRun(base / "slurm", base / "cluster-run", base / "cluster.json")
    config.posefix_cluster.start()
    signal.signal(signal.SIGTERM, _interrupt)  # killed, the session still stops the cluster (pytest_sessionfinish)


def _interrupt(signum, frame):
    """SIGTERM as Ctrl-C: pytest ends the session as interrupted, and :func:`pytest_sessionfinish` runs."""
    raise KeyboardInterrupt


def pytest_sessionfinish(session, exitstatus):
    """Stop the SLURM run this process started (always: also after a failure or an interrupt, then at once)."""
    run = getattr(session.config, "posefix_cluster", None)
    if run:
        run.stop(wait=exitstatus != pytest.ExitCode.INTERRUPTED)

