"""Rig files: the shipped example reads; malformed files fail with one line naming the file and the problem."""

import numpy as np
import pytest

from conftest import ROOT
from posefix.io.errors import InputError
from posefix.medial.rig_files import read_rig


def test_the_demo_rig_reads_with_its_joints_and_poses():
    rig, poses = read_rig(ROOT / "examples" / "demo-limb.yaml")
    assert rig.names == ("root", "j1", "j2", "tip") and rig.parents.tolist() == [-1, 0, 1, 2]
    assert rig.bones.tolist() == [[0, 1], [1, 2], [2, 3]]
    assert np.allclose(poses["demo-02"].rotations[1] @ [0, 0, 1.0], [np.sin(np.radians(120)), 0, np.cos(np.radians(120))])


@pytest.mark.parametrize("text, problem", [
    ("joints: [", "not valid YAML"),
    ("poses: {a: {}}", "needs 'joints' and 'poses'"),
    ("joints: {a: {position: [0, 0]}}\nposes: {p: {}}", "'position' must be three numbers"),
    ("joints: {a: {position: [0, 0, 0], parent: b}}\nposes: {p: {}}", "parent 'b' is not a joint listed before"),
    ("joints: {a: {position: [0, 0, 0]}, b: {position: [1, 0, 0]}}\nposes: {p: {}}", "exactly one root"),
    ("joints: {a: {position: [0, 0, 0]}}\nposes: {p: {rotations: {z: [1, 0, 0]}}}", "unknown joint(s) z"),
    ("joints: {a: {position: [0, 0, 0]}}\nposes: {p: {rotations: {a: [1, 0]}}}", "rotations are [x, y, z]"),
])
def test_malformed_rig_files_name_the_file_and_the_problem(tmp_path, text, problem):
    path = tmp_path / "rig.yaml"
    path.write_text(text)
    with pytest.raises(InputError, match="rig.yaml") as err:
        read_rig(path)
    assert problem in str(err.value)
