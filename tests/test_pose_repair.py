"""posefix.repair_pose (issue 49, item 2): one pose repaired in memory has the pipeline's vertices; bad arrays and
settings are refused with one ``PosefixError`` line naming the argument or key."""

import numpy as np
import pytest

import posefix
from posefix.io.artifacts import read_artifact
from posefix.io.meshes import read_mesh
from posefix.mesh.geometry import bbox_diagonal
from posefix.workflow.demo import demo_library


@pytest.mark.pipeline
def test_a_pose_repaired_in_memory_has_the_pipelines_vertices(demo_run):
    folder = demo_run / "data" / "demo"
    V, F = read_mesh(folder / "demo-reference.obj")
    target, _ = read_mesh(folder / "demo-02.ply")
    result = posefix.repair_pose(V, F, target)
    repaired = read_artifact(demo_run / "results" / "demo" / "demo-02" / "verify.h5", "verify", ["repaired"])[0]
    assert np.abs(result.V - repaired["repaired"]).max() <= 1e-12 * bbox_diagonal(V)
    assert set(result.seconds) == {"keyframes", "classify", "constraints", "fit", "integrate", "verify"}
    assert result.metrics["repaired_new"] == 0 and result.status == "ok"


@pytest.fixture(scope="module")
def limb():
    return demo_library(around=12)


@pytest.mark.parametrize("arguments, line", [
    (lambda V, F, T: (V, F, T[:10]), "V_target: 10 vertices, the reference has 362"),
    (lambda V, F, T: (V, F.astype(float), T), "F: float64 indices, expected integers"),
    (lambda V, F, T: (V, F, T * np.nan), "V_target: 362 of 362 rows with NaN or infinite values (first: row 0)"),
    (lambda V, F, T: (V[:, :2], F, T), "V_reference: shape (362, 2), expected (k, 3)"),
    (lambda V, F, T: (V, F + 1, T), "F: a vertex index out of range 0..361"),
])
def test_repair_pose_refuses_bad_arrays_in_one_line_naming_the_argument(limb, arguments, line):
    V, F, poses = limb
    with pytest.raises(posefix.PosefixError) as caught:
        posefix.repair_pose(*arguments(V, F, poses["demo-01"]))
    assert str(caught.value) == line


@pytest.mark.parametrize("settings, line", [
    ({"verify.finsh": "snap"}, "settings: verify.finsh: unknown key (did you mean 'finish'?)"),
    ({"fit": {"batch": 0}}, "settings: fit.batch: 0 is less than the minimum of 1"),
])
def test_repair_pose_refuses_bad_settings_in_one_line_naming_the_key(limb, settings, line):
    V, F, poses = limb
    with pytest.raises(posefix.PosefixError) as caught:
        posefix.repair_pose(V, F, poses["demo-01"], settings)
    assert str(caught.value) == line
