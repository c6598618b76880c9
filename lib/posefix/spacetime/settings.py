"""The space-time stages' settings, declared once (config sections ``keyframes``, ``classify``, ``constraints``,
``integrate``): each field's default (the library function's where the stage passes it on unchanged), help, unit and
bounds, from which ``posefix.workflow.settings`` makes the stages' options and the config schema's sections.
Lengths with unit ``d`` are relative to the reference's bounding-box diagonal; the stage scales them."""

import inspect
from dataclasses import dataclass, field

from posefix.spacetime.classification import constraint_mask
from posefix.spacetime.constraints import spacetime_constraints
from posefix.spacetime.integration import rk45
from posefix.spacetime.keyframes import keyframes, prepare


def library_default(function, name):
    """The default of parameter ``name`` of ``function``: a setting that the stage passes on as it is."""
    return inspect.signature(function).parameters[name].default


@dataclass(frozen=True)
class KeyframesSettings:
    """Stage keyframes: the key frames from the reference to a target (S0 §4.1)."""

    count: int = field(default=library_default(keyframes, "count"), metadata={
        "help": "number of key frames K", "minimum": 2, "cite": "11 in S0 §4.1"})
    align: bool = field(default=library_default(prepare, "align"), metadata={
        "help": "remove the global rigid motion before the per-face interpolation"})
    unwrap: bool = field(default=library_default(prepare, "unwrap"), metadata={
        "help": "unwrap rotation branches over the face adjacency (else principal branches)"})


@dataclass(frozen=True)
class ClassifySettings:
    """Stage classify: the constrained vertices V_C (S0 §4.1)."""

    ring: int = field(default=library_default(constraint_mask, "ring"), metadata={
        "help": "rings removed around intersecting vertices", "minimum": 0, "cite": "1 in S0 §4.1"})
    contact: float = field(default=0.02, metadata={
        "help": "near-contact distance (0 turns it off)", "unit": "d", "minimum": 0})
    contact_radius: float = field(default=0.1, metadata={
        "help": "geodesic neighbourhood radius of a near contact", "unit": "d", "exclusiveMinimum": 0})


@dataclass(frozen=True)
class ConstraintsSettings:
    """Stage constraints: the space-time constraints of the vector field (S0 §4.1)."""

    samples: int = field(default=library_default(spacetime_constraints, "samples"), metadata={
        "help": "s: constraints at t_i = i/s, i = 0..s", "minimum": 2, "cite": "12 in S0 §4.1"})
    tau: float = field(default=0.3, metadata={"help": "time-axis scale", "unit": "d", "exclusiveMinimum": 0})
    tangents: str = field(default=library_default(spacetime_constraints, "tangents"), metadata={
        "help": "knot tangents: hermite (finite differences, the paper's) or spline (a per-vertex cubic spline)",
        "choices": ("hermite", "spline"), "cite": "S0 §4.1"})


@dataclass(frozen=True)
class IntegrateSettings:
    """Stage integrate: every reference vertex through the fitted field by RK45 (S0 §4.3)."""

    device: str = field(default="auto", metadata={
        "help": "OpenCL device type (cpu, gpu: that one or an error; auto: a GPU, else a CPU, else numpy with a "
                "warning), or the numpy backend", "choices": ("auto", "cpu", "gpu", "numpy")})
    rtol: float = field(default=library_default(rk45, "rtol"), metadata={
        "help": "relative tolerance per RK45 step", "exclusiveMinimum": 0})
    atol_rel: float = field(default=1e-7, metadata={
        "help": "absolute tolerance per step (1e-3 eps)", "unit": "d", "exclusiveMinimum": 0})
    h0: float = field(default=library_default(rk45, "h0"), metadata={
        "help": "first step size (time units)", "exclusiveMinimum": 0, "maximum": 1})
    vec: int = field(default=0, metadata={"help": "OpenCL vector width over centres (0: from the device)",
                                          "minimum": 0})
