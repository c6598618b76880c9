"""Config problems: one line each, naming the key path and what is allowed; unknown keys with a suggestion."""

import copy

import pytest
import yaml

from conftest import ROOT
from posefix.workflow.config_check import config_problems, folder_problem, folder_problems, typed_by_schema

SCHEMA = yaml.safe_load((ROOT / "schemas" / "config.schema.yaml").read_text())
CONFIG = yaml.safe_load((ROOT / "config.yaml").read_text())


def test_the_shipped_config_has_no_problem():
    assert config_problems(CONFIG, SCHEMA) == []


def test_every_problem_is_one_line_naming_its_key():
    config = copy.deepcopy(CONFIG)
    config["keyframes"]["count"] = 1
    config["integrate"]["device"] = "tpu"
    config["fit"]["max_centres"] = 3
    config["keyframs"] = {}
    config["baselines"] = ["medial", "volumetrc"]
    assert config_problems(config, SCHEMA) == [
        "baselines.1: 'volumetrc' is not one of 'medial', 'volumetric', 'contact'",
        "fit.max_centres: unknown key (did you mean 'max_centers'?)",
        "integrate.device: 'tpu' is not one of 'auto', 'cpu', 'gpu', 'numpy'",
        "keyframes.count: 1 is less than the minimum of 2",
        "keyframs: unknown key (did you mean 'keyframes'?)",
    ]


def test_text_from_the_command_line_takes_the_schema_types_at_its_place():
    schema = SCHEMA
    given = {"baselines": "medial,contact", "poses": "a,b",  # what Snakemake's --config leaves as text
             "downstream": {"alphas": ["1.0"], "k_bend": ["1e-05", "0.01"], "baselines": "true", "max_iters": "20"},
             "classify": {"exclude": {"demo-01": ["3", "4"], "demo-02": "ids.txt"}, "contact": "0"},
             "skeletal_pose": {"rig": "null", "mesh": "me.obj"}, "fit": {"threads": 2}}
    assert typed_by_schema(given, schema) == {
        "baselines": ["medial", "contact"], "poses": "a,b",
        "downstream": {"alphas": [1.0], "k_bend": [1e-05, 0.01], "baselines": True, "max_iters": 20},
        "classify": {"exclude": {"demo-01": [3, 4], "demo-02": "ids.txt"}, "contact": 0.0},
        "skeletal_pose": {"rig": None, "mesh": "me.obj"}, "fit": {"threads": 2}}
    assert typed_by_schema({"fit": {"threads": "two"}}, schema) == {"fit": {"threads": "two"}}  # the check names it


@pytest.mark.parametrize("name", ["..", ".", "a/b", ".hidden", "x y", "{p}"])
def test_a_name_that_is_not_a_plain_folder_name_is_refused_in_one_line(name):
    assert config_problems({"name": name}, SCHEMA) == [
        f"name: {name!r} is not a plain name (letters, digits, '.', '_' and '-', not starting with '.')"]
    assert config_problems({"name": "lion-2.b_1"}, SCHEMA) == []


def test_a_folder_that_cannot_be_made_is_one_line_naming_why(tmp_path):
    (tmp_path / "a-file").write_text("")
    assert folder_problem(tmp_path / "new" / "deeper") is None and not (tmp_path / "new").exists()
    assert folder_problem(tmp_path / "a-file" / "reports") == f"{tmp_path / 'a-file' / 'reports'} cannot be made: " \
                                                              f"{tmp_path / 'a-file'} is a file"
    assert folder_problems({"results": "/proc/posefix", "reports": str(tmp_path)}, "lib") == [
        "results=/proc/posefix: /proc/posefix/lib cannot be made: /proc takes no new folder (No such file or "
        "directory)"]
    assert list(tmp_path.iterdir()) == [tmp_path / "a-file"]  # the folders made to try are gone
