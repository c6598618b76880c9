"""The run's plan (posefix.workflow.plan): the library a config names, the reference's size, the summary's poses and
the workflow's targets, as rules/common.smk gets them."""

import doctest

import numpy as np
import pytest
import trimesh

from posefix.io.artifacts import write_artifact
from posefix.workflow import plan

CONFIG = {"library": None, "reference": None, "name": None, "results": "results", "mesh": None,
          "demo": {"folder": "demo"}}


def test_the_examples_of_the_plan_hold():
    assert doctest.testmod(plan).failed == 0


def _sphere(path):
    """A 42-vertex sphere written to ``path``."""
    s = trimesh.creation.icosphere(subdivisions=1)
    trimesh.Trimesh(s.vertices, s.faces, process=False).export(path)


def test_a_folder_library_its_poses_and_a_pose_it_lacks_in_one_line(tmp_path):
    for name in ("rest", "walk", "run"):
        _sphere(tmp_path / f"{name}.obj")
    config = CONFIG | {"library": str(tmp_path), "reference": "rest.obj"}
    assert [p.name for p in plan.library(config, None).poses] == ["run", "walk"]
    assert [p.name for p in plan.library(config, ["walk"]).poses] == ["walk"]
    with pytest.raises(SystemExit) as refused, plan.exit_on_input_error():
        plan.library(config, ["jump"])
    assert str(refused.value).startswith("posefix: error: ") and "jump" in str(refused.value)


def test_the_demo_library_refuses_a_pose_it_does_not_have():
    assert plan.library(CONFIG, ["demo-02"]).name == "demo"
    with pytest.raises(SystemExit, match=r"^posefix: error: demo: pose\(s\) not in the demo library: demo-9$"), \
            plan.exit_on_input_error():
        plan.library(CONFIG, ["demo-9", "demo-01"])


def test_the_reference_size_comes_from_its_validated_artifact_when_newer_else_from_the_file(tmp_path):
    for name in ("rest", "walk"):
        _sphere(tmp_path / f"{name}.obj")
    lib = plan.library(CONFIG | {"library": str(tmp_path), "reference": "rest.obj"}, None)
    results = tmp_path / "results"
    assert plan.read_reference_vertices(results, lib) == {"n": 42}
    results.mkdir()
    write_artifact(results / "reference.h5", "validate", {"vertices": np.zeros((3, 3))}, params={}, inputs=[],
                   timings={}, metrics={"vertices": 3})
    assert plan.read_reference_vertices(results, lib) == {"n": 3}  # validate_reference's count, the file unread
    (tmp_path / "rest.obj").write_text("v 0 0\n")
    assert plan.read_reference_vertices(tmp_path / "none", lib)["error"].path == str(tmp_path / "rest.obj")
    (tmp_path / "rest.obj").unlink()  # not there yet (the demo's files are written by a rule): no refusal
    assert plan.read_reference_vertices(tmp_path / "none", lib) == {"error": None}


def test_the_repairs_containers_and_the_report_are_the_targets_of_a_container_library():
    assert plan.repaired_container_files("r/walk", "/data/walk.usdc", ["contact"]) == [
        "r/walk/repaired/walk.usdc", "r/walk/repaired-contact/walk.usdc"]
    assert plan.repaired_container_files("r/walk", None, ["contact"]) == []
    figure = plan.figure_report("rep/lib", "fit", "RBF fit")
    assert figure["value"] == "rep/lib/figures/{pose}/fit.png" and figure["caption"] == "captions/fit.rst"
