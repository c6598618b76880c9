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
    config["repairs"] = ["medial", "volumetrc"]
    assert config_problems(config, SCHEMA) == [
        "fit.max_centres: unknown key (did you mean 'max_centers'?)",
        "integrate.device: 'tpu' is not one of 'auto', 'cpu', 'gpu', 'numpy'",
        "keyframes.count: 1 is less than the minimum of 2",
        "keyframs: unknown key (did you mean 'keyframes'?)",
        "repairs.1: 'volumetrc' is not one of 'medial', 'volumetric', 'contact'",
    ]


def test_text_from_the_command_line_takes_the_schema_types_at_its_place():
    schema = SCHEMA
    given = {"repairs": "medial,contact", "poses": "a,b",  # what Snakemake's --config leaves as text
             "downstream": {"alphas": ["1.0"], "k_bend": ["1e-05", "0.01"], "repairs": "true", "max_iters": "20"},
             "classify": {"exclude": {"demo-01": ["3", "4"], "demo-02": "ids.txt"}, "contact": "0"},
             "medial": {"pose": {"rig": "null", "mesh": "me.obj"}}, "fit": {"threads": 2}}
    assert typed_by_schema(given, schema) == {
        "repairs": ["medial", "contact"], "poses": "a,b",
        "downstream": {"alphas": [1.0], "k_bend": [1e-05, 0.01], "repairs": True, "max_iters": 20},
        "classify": {"exclude": {"demo-01": [3, 4], "demo-02": "ids.txt"}, "contact": 0.0},
        "medial": {"pose": {"rig": None, "mesh": "me.obj"}}, "fit": {"threads": 2}}
    assert typed_by_schema({"fit": {"threads": "two"}}, schema) == {"fit": {"threads": "two"}}  # the check names it


def test_the_keys_renamed_in_2026_12_are_read_at_their_new_places_with_one_notice_each():
    from posefix.workflow.config_check import RENAMED_KEYS, renamed_config
    defaults = yaml.safe_load((ROOT / "config.yaml").read_text())
    old = {"baselines": ["contact"], "repair_medial": {"max_iters": 5}, "repair_volumetric": {"max_rings": 2},
           "volumetric_pose": {"frames": 2}, "volumetric_animate": {"iterations": 1}, "repair_contact": {"threads": 2},
           "skeletal_pose": {"smooth_iters": 3, "falloff": 0.3}}
    given = {**defaults, **old, "downstream": {**defaults["downstream"], "baselines": True}}
    config, notices = renamed_config(given)
    assert config_problems(config, SCHEMA) == [] and len(notices) == len(RENAMED_KEYS)
    assert (config["repairs"], config["medial"]["repair"]["max_iters"], config["volumetric"]["repair"]["max_rings"],
            config["volumetric"]["pose"]["frames"], config["volumetric"]["animate"]["iterations"],
            config["contact"]["repair"]["threads"], config["medial"]["skeleton"]["smooth_iters"],
            config["medial"]["pose"]["falloff"], config["downstream"]["repairs"]) == (
        ["contact"], 5, 2, 2, 1, 2, 3, 0.3, True)
    assert config["medial"]["repair"]["tau"] == defaults["medial"]["repair"]["tau"]  # the others kept
    assert "posefix: config key 'skeletal_pose' is now 'medial.pose and medial.skeleton' (the old key goes in the " \
           "next release)" in notices
    assert renamed_config(defaults) == (defaults, [])


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
