"""Defaults in one place: config.yaml equals the schema's defaults, the stages' and the library's.

config.yaml (validated by schemas/config.schema.yaml) is the source. Every tunable a stage takes has
the same argparse default, and every library function or settings class that takes it has the
same default, or none where the library works in other units (lengths in the input's units, where
the config is relative to the bbox diagonal).
"""

import dataclasses
import importlib.util
import inspect

import pytest
import yaml

from conftest import ROOT
from posefix.downstream.check import deform_towards, downstream_check
from posefix.downstream.gauss_newton import SolverSettings
from posefix.mesh.shells import shell_energy
from posefix.mesh.contact_solver import ContactSettings
from posefix.mesh.contacts import contact_vertices
from posefix.mesh.distortion import distortion_summary
from posefix.workflow.demo import demo_library
from posefix.verify.contact_finish import FinishSettings
from posefix.verify.sequence import RepairSettings
from posefix.medial.authoring import SkeletalPoser
from posefix.medial.flow import MedialBallFlow, candidate_balls, medial_ball_flow, nearest_balls
from posefix.medial.reconstruction import SkeletalReconstruction, collapsed_faces, frame_maps
from posefix.medial.repair import MedialRepair, medial_repair
from posefix.medial.rig import skinning_weights
from posefix.medial.skeletal_mesh import skeletal_mesh
from posefix.spacetime.classification import constraint_mask
from posefix.volumetric.authoring import VolumetricPoser
from posefix.volumetric.repair import VolumetricRepair
from posefix.volumetric.markers import MarkerAnimator
from posefix.volumetric.tet_mesh import tet_mesh
from posefix.spacetime.constraints import knot_tangents, spacetime_constraints
from posefix.spacetime.fit import FitSettings
from posefix.spacetime.integration import rk45
from posefix.spacetime.integration_opencl import OpenCLIntegrator, rk45_opencl
from posefix.spacetime.keyframes import keyframes, prepare

CONFIG = yaml.safe_load((ROOT / "config.yaml").read_text())
SCHEMA = yaml.safe_load((ROOT / "schemas" / "config.schema.yaml").read_text())
def leaf_sections(config, prefix=""):
    """``{dotted section: {key: value}}`` of the settings in ``config`` (nested sections flattened), dict."""
    out = {}
    for name, value in config.items():
        if isinstance(value, dict) and name not in ("exclude", "rigid"):
            settings = {k: v for k, v in value.items() if not isinstance(v, dict) or k in ("exclude", "rigid")}
            if settings:
                out[prefix + name] = settings
            out |= leaf_sections({k: v for k, v in value.items() if k not in settings}, f"{prefix}{name}.")
    return out


SECTIONS = leaf_sections(CONFIG)
NONE = inspect.Parameter.empty


def default(owner, name):
    """Default of parameter ``name`` of a function, or of field ``name`` of a dataclass (NONE if it has none)."""
    if dataclasses.is_dataclass(owner):
        field = {f.name: f for f in dataclasses.fields(owner)}[name]
        return NONE if field.default is dataclasses.MISSING else field.default
    return inspect.signature(owner).parameters[name].default


# (section, key) -> where the library takes the same value: [(function or dataclass, parameter, convert)]
LIBRARY = {
    ("demo", "seed"): [(demo_library, "seed", None)],
    ("demo", "around"): [(demo_library, "around", None)],
    ("keyframes", "count"): [(keyframes, "count", None)],
    ("keyframes", "align"): [(keyframes, "align", None), (prepare, "align", None)],
    ("keyframes", "unwrap"): [(keyframes, "unwrap", None), (prepare, "unwrap", None)],
    ("classify", "ring"): [(constraint_mask, "ring", None)],
    ("constraints", "samples"): [(spacetime_constraints, "samples", None)],
    ("constraints", "tangents"): [(spacetime_constraints, "tangents", None), (knot_tangents, "method", None)],
    ("fit", "eps_rms_rel"): [(FitSettings, "eps_rms", None)],  # 0: off, in any unit
    ("fit", "max_centers"): [(FitSettings, "max_centers", None)],
    ("fit", "candidates"): [(FitSettings, "candidates", None)],
    ("fit", "batch"): [(FitSettings, "batch", None)],
    ("fit", "selection"): [(FitSettings, "selection", None)],
    ("fit", "update"): [(FitSettings, "update", None)],
    ("fit", "memory_gb"): [(FitSettings, "memory_bytes", lambda b: b / 1e9)],
    ("integrate", "rtol"): [(rk45, "rtol", None)],
    ("integrate", "h0"): [(rk45, "h0", None), (rk45_opencl, "h0", None),
                          (OpenCLIntegrator.integrate, "h0", None)],
    ("integrate", "vec"): [(OpenCLIntegrator, "vec", lambda v: v or 0)],  # None and 0: the device's width
    **{("verify", f.name): [(RepairSettings, f.name, None)] for f in dataclasses.fields(RepairSettings)},
    **{("verify", f.name): [(FinishSettings, f.name, None)] for f in dataclasses.fields(FinishSettings)},
    **{("contact", f.name): [(ContactSettings, f.name, None)] for f in dataclasses.fields(ContactSettings)},
    ("summary", "distortion_limit"): [(distortion_summary, "limit", None)],
    ("downstream", "alphas"): [(downstream_check, "alphas", list)],
    ("downstream", "k_bend"): [(downstream_check, "k_bend", list)],
    ("downstream", "k_stretch"): [(downstream_check, "k_stretch", None), (deform_towards, "k_stretch", None),
                                  (shell_energy, "k_stretch", None)],
    ("downstream", "max_iters"): [(SolverSettings, "max_iters", None)],
    ("downstream", "rel_tol"): [(SolverSettings, "rel_tol", None)],
    ("downstream", "stall_iters"): [(SolverSettings, "stall_iters", None)],
    ("medial.skeleton", "medial"): [(skeletal_mesh, "medial", None)],
    ("medial.skeleton", "tol"): [(skeletal_mesh, "tol", None)],
    ("medial.skeleton", "smooth_iters"): [(skeletal_mesh, "smooth_iters", None)],
    ("medial.skeleton", "smooth_step"): [(skeletal_mesh, "smooth_step", None)],
    ("medial.pose", "falloff"): [(SkeletalPoser, "falloff", None), (skinning_weights, "falloff", None)],
    ("medial.pose", "min_sine"): [(SkeletalPoser, "min_sine", None), (frame_maps, "min_sine", None)],
    ("medial.pose", "min_area"): [(SkeletalPoser, "min_area", None), (SkeletalReconstruction, "min_area", None),
                                    (collapsed_faces, "min_area", None)],
    ("medial.pose", "tau"): [(SkeletalPoser.author, "tau", None), (MedialBallFlow, "tau", None),
                               (medial_ball_flow, "tau", None)],
    ("medial.pose", "neighbours"): [(SkeletalPoser.author, "neighbours", None), (MedialBallFlow, "neighbours", None),
                                      (medial_ball_flow, "neighbours", None), (nearest_balls, "neighbours", None),
                                      (candidate_balls, "neighbours", None)],
    ("medial.pose", "max_iters"): [(SkeletalPoser.author, "max_iters", None), (MedialBallFlow.run, "max_iters", None),
                                     (medial_ball_flow, "max_iters", None)],
    **{("medial.repair", key): [(MedialRepair, key, None)]  # medial_repair passes them on
       for key in ("tau", "neighbours", "max_reach")},
    ("medial.repair", "max_iters"): [(MedialRepair.repair, "max_iters", None), (medial_repair, "max_iters", None)],
    ("volumetric.pose", "tet_vertices"): [(tet_mesh, "surface_vertices", None)],
    ("volumetric.pose", "iterations"): [(VolumetricPoser.pose, "iterations", None)],
    ("volumetric.pose", "frames"): [(VolumetricPoser.pose, "frames", None)],
    ("volumetric.repair", "tet_vertices"): [(tet_mesh, "surface_vertices", None)],
    **{("volumetric.repair", key): [(VolumetricRepair.repair, key, None)]
       for key in ("iterations", "point_weight", "max_rings", "max_free")},
    ("volumetric.animate", "tet_vertices"): [(tet_mesh, "surface_vertices", None)],
    ("volumetric.animate", "iterations"): [(MarkerAnimator.animate, "iterations", None)],
    ("volumetric.animate", "first_iterations"): [(MarkerAnimator.animate, "first_iterations", None)],
}
# relative to the bbox diagonal in the config, lengths in the library: the library has no default
RELATIVE = {
    ("classify", "contact"): [(contact_vertices, "distance")],
    ("classify", "contact_radius"): [(contact_vertices, "radius")],
    ("constraints", "tau"): [(spacetime_constraints, "tau")],
    ("fit", "eps_rel"): [(FitSettings, "eps")],
    ("integrate", "atol_rel"): [(rk45, "atol"), (rk45_opencl, "atol"), (OpenCLIntegrator.integrate, "atol")],
    ("medial.pose", "margin"): [(MedialBallFlow, "margin"), (medial_ball_flow, "margin"),
                                  (SkeletalPoser.author, "margin")],
    ("medial.repair", "margin"): [(MedialRepair, "margin"), (medial_repair, "margin")],
}
STAGE_ONLY = {("integrate", "device"), ("fit", "device"), ("fit", "keep_checkpoint"), ("volumetric.animate", "attach"),
              ("volumetric.animate", "max_offset")}
"""Options of a stage with no library counterpart: checked against the stage's default only."""
WORKFLOW_ONLY = {("demo", "folder"), ("classify", "exclude"), ("integrate", "device"), ("fit", "device"), ("medial.pose", "rig"),
                 ("medial.pose", "mesh"), ("medial.pose", "out"), ("downstream", "repairs"),
                 ("volumetric.pose", "script"), ("volumetric.pose", "mesh"), ("volumetric.pose", "out"),
                 ("volumetric.repair", "tet_vertices"), ("volumetric.animate", "tracks"), ("volumetric.animate", "mesh"),
                 ("volumetric.animate", "out"), ("volumetric.animate", "rigid")} | STAGE_ONLY | {
    (section, "threads") for section, value in SECTIONS.items() if "threads" in value}
"""Keys of the workflow (paths, per-pose inputs, rule threads) or of a stage only (the OpenCL device choice);
volumetric.repair.tet_vertices goes to stage tet_mesh (its library default is checked in LIBRARY)."""


SECTION_STAGES = {"contact": ["verify", "repair_contact"], "contact.repair": ["repair_contact"],
                  "summary": ["summary", "render"], "medial.skeleton": ["skeleton", "skeletal_pose"],
                  "medial.repair": ["repair_medial"], "medial.pose": ["skeletal_pose"],
                  "volumetric.repair": ["repair_volumetric"], "volumetric.pose": ["volumetric_pose"],
                  "volumetric.animate": ["volumetric_animate"]}
"""Config sections read by other stages than the one of their name."""


def tunables():
    return [(s, k) for s, section in SECTIONS.items() for k in section]


def _stage_parser(stage):
    spec = importlib.util.spec_from_file_location(f"stage_{stage}", ROOT / "stages" / f"{stage}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.build_parser()


def test_config_yaml_holds_exactly_the_schemas_keys_with_its_defaults():
    def check(config, props, prefix):
        assert set(config) == set(props), prefix
        for key, prop in props.items():
            if prop.get("type") == "object" and "properties" in prop:
                check(config[key], prop["properties"], f"{prefix}{key}.")
            else:
                assert config[key] == prop["default"], prefix + key
    check(CONFIG, SCHEMA["properties"], "")


def test_every_tunable_is_accounted_for():
    assert set(tunables()) == set(LIBRARY) | set(RELATIVE) | WORKFLOW_ONLY


@pytest.mark.parametrize("section", sorted({s for s, _ in tunables()}))
def test_stage_defaults_equal_the_config(section):
    for stage in SECTION_STAGES.get(section, [section]):
        parser = _stage_parser(stage)
        for s, key in tunables():
            if s == section and (s, key) not in WORKFLOW_ONLY - STAGE_ONLY:
                assert parser.get_default(key) == SECTIONS[s][key], f"stages/{stage}.py --{key.replace('_', '-')}"


@pytest.mark.parametrize("key", sorted(LIBRARY), ids="{0[0]}.{0[1]}".format)
def test_library_defaults_equal_the_config(key):
    for owner, name, convert in LIBRARY[key]:
        value = default(owner, name)
        assert value is not NONE, f"{owner.__name__}({name}) has no default"
        assert (convert or (lambda v: v))(value) == SECTIONS[key[0]][key[1]], f"{owner.__name__}({name}={value!r})"


@pytest.mark.parametrize("key", sorted(RELATIVE), ids="{0[0]}.{0[1]}".format)
def test_relative_tunables_have_no_library_default(key):
    for owner, name in RELATIVE[key]:
        assert default(owner, name) is NONE, f"{owner.__name__}({name}) has a default in other units"
