"""The workflow on pose libraries in one USD, glTF or Alembic file (issues 31, 49): the demo limb (at 12 vertices per
ring instead of 40, 362 vertices: a quicker repair) stored as USD frames, USD blend shapes, glTF morph targets and
Alembic frames (written by Blender: where the bpy environment .venv-blender is) repairs exactly as the same
coordinates in OBJ files, and each repair goes back into a file of the input's kind. (The lion library as one USD,
GLB and Alembic file against its folder: `make bench`, benchmarks/containers.py.)"""

import json

import numpy as np
import pytest

from conftest import ROOT, snakemake
from containers import write_alembic_frames, write_gltf, write_usd_blend_shapes, write_usd_frames
from posefix.io.containers import open_container
from posefix.io.meshes import read_mesh, write_mesh
from posefix.workflow.demo import demo_library
from posefix.report.tables import entry_status

pytestmark = pytest.mark.pipeline

POSES = ("demo-02", "demo-03")
"""The demo poses these runs repair (two, to keep the four runs short; 29 and 64 pairs of faces intersecting at 362
vertices), with the contact repair beside S0."""
RUN = ("repairs=[contact]", "downstream={'max_iters': 1}")
"""Their config: one downstream step (the repaired meshes do not depend on the check)."""
BLENDER_PYTHON = ROOT / ".venv-blender" / "bin" / "python"
"""The bpy environment that reads and writes Alembic (the workflow finds it in the checkout)."""


def targets(name, path):
    """What the runs make of library ``name`` (no figures, no viewer): its summary and, for a folder ``path``, each
    repair's meshes, for a file each repair's file (which needs the meshes)."""
    made = [f"reports/{name}/summary.json"]
    if path.is_dir():
        return made + [f"results/{name}/{r}/{p}.obj" for r in ("repaired", "repaired-contact") for p in POSES]
    return made + [f"results/{name}/{r}/{path.name}" for r in ("repaired", "repaired-contact")]


def on_grid(X):
    """``X`` rounded to multiples of 2^-16: exact in float32, and so are the differences of two such points
    (the demo limb is within 2^7 of the origin), so frames, blend shape offsets and morph target displacements all
    hold exactly these coordinates."""
    return np.round(np.asarray(X) * 2.0 ** 16) / 2.0 ** 16


@pytest.fixture(scope="module")
def limb(tmp_path_factory):
    """The demo limb on the grid: the OBJ folder's run and the three containers' runs, {kind: (work, file)}."""
    V_ref, F, poses = demo_library(around=12)
    V_ref, chosen = on_grid(V_ref), [on_grid(poses[p]) for p in POSES]
    work = tmp_path_factory.mktemp("containers")
    folder = work / "limb"
    write_mesh(folder / "limb-reference.obj", V_ref, F)
    for name, V in zip(POSES, chosen):
        write_mesh(folder / f"{name}.obj", V, F)
    files = {"obj": folder,
             "usd frames": write_usd_frames(work / "frames.usda", V_ref, chosen, F),
             "usd blend shapes": write_usd_blend_shapes(work / "shapes.usdc", V_ref, chosen, F, POSES, sparse=(0,)),
             "glb": write_gltf(work / "targets.glb", V_ref, chosen, F, POSES, sparse=(1,))}
    if BLENDER_PYTHON.is_file():
        with pytest.MonkeyPatch.context() as env:
            env.setenv("POSEFIX_BLENDER", str(BLENDER_PYTHON))
            files["abc"] = write_alembic_frames(work / "frames.abc", V_ref, chosen, F)
    runs = {}
    for kind, path in files.items():
        run = work / kind.replace(" ", "-")
        proc = snakemake(run, *targets("limb" if kind == "obj" else path.stem, path), "--config", f"library={path}",
                         *RUN)
        assert proc.returncode == 0, (kind, proc.stderr[-3000:])
        runs[kind] = (run, path)
    return runs


def _repaired(run, name, repair, pose):
    return read_mesh(run / "results" / name / repair / f"{pose}.ply")


@pytest.mark.parametrize("kind", ["usd frames", "usd blend shapes", "glb", "abc"])
def test_a_container_repairs_bit_for_bit_as_obj_files_and_is_written_back(limb, kind, monkeypatch):
    if kind not in limb:
        pytest.skip(f"no bpy environment at {BLENDER_PYTHON} to read and write Alembic (make test makes it)")
    monkeypatch.setenv("POSEFIX_BLENDER", str(BLENDER_PYTHON))
    (obj_run, _), (run, path) = limb["obj"], limb[kind]
    name = path.stem
    box = open_container(path)
    reference = box.rest or next(iter(box.members))  # an Alembic cache's first frame
    members = [m for m in box.members if m != reference]  # frames-1, frames-2 or the demo pose names
    summary = json.loads((run / "reports" / name / "summary.json").read_text())
    assert [e["pose"] for e in summary["poses"]] == members
    for repair in ("repaired", "repaired-contact"):
        back = open_container(run / "results" / name / repair / path.name)
        assert list(back.members) == list(box.members) and back.mesh == box.mesh and back.n == box.n
        assert np.array_equal(back.faces, box.faces)
        for member, pose in zip(members, POSES):
            X, F = read_mesh(obj_run / "results" / "limb" / repair / f"{pose}.obj")
            V, F2 = _repaired(run, name, repair, member)
            assert np.array_equal(V, X) and np.array_equal(F, F2), (kind, repair, pose)  # bit for bit
            if kind in ("usd frames", "abc"):  # point3f[], Alembic's P: the float32 of the repaired positions
                assert np.array_equal(back.points(member), X.astype(np.float32).astype(np.float64))
            else:  # float32 base plus float32 offsets
                np.testing.assert_allclose(back.points(member), X, rtol=0, atol=4e-7 * np.abs(X).max())


def summary_counts(run, name):
    """Each pose's status (ok, fallback, check) and intersecting-face counts in the summary of library ``name`` run
    in ``run``."""
    summary = json.loads((run / "reports" / name / "summary.json").read_text())
    return [(entry_status(e)[0], e["intersecting_faces"]) for e in summary["poses"]]


def test_the_summary_counts_the_same_for_a_container_and_its_obj_files(limb):
    counts = {kind: summary_counts(run, "limb" if kind == "obj" else path.stem) for kind, (run, path) in limb.items()}
    assert all(c == counts["obj"] for c in counts.values()), counts


def test_changing_one_frame_of_the_file_reruns_only_that_pose(limb):
    run, path = limb["usd frames"]
    original = path.read_bytes()
    try:
        from pxr import Usd, UsdGeom, Vt
        stage = Usd.Stage.Open(str(path))
        points = UsdGeom.Mesh(stage.GetPrimAtPath("/Character/Body")).GetPointsAttr()
        moved = np.array(points.Get(2), dtype=np.float32)
        moved[0] += 0.001
        points.Set(Vt.Vec3fArray.FromNumpy(moved), 2)
        stage.GetRootLayer().Save()
        proc = snakemake(run, "-n", *targets(path.stem, path), "--config", f"library={path}", *RUN)
        assert proc.returncode == 0, proc.stderr[-3000:]
        jobs = dict(line.split() for line in proc.stdout.split("Job stats:")[1].split("total")[0].splitlines()[3:]
                    if line.strip())
        assert jobs["unpack"] == "1" and jobs["fit"] == "1" and jobs["pack"] == "2", jobs  # frame 2 alone
        assert "member=frames-2" in proc.stdout and "member=frames-1" not in proc.stdout
        assert "pose=frames-1" not in proc.stdout
    finally:
        path.write_bytes(original)
