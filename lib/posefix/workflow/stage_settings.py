"""The stages' settings, declared once where no library settings class holds them (config sections ``keyframes``,
``classify``, ``constraints``, ``integrate``, ``medial.skeleton``, ``medial.repair``, ``volumetric.repair``): each
field's default (the library function's, where the stage passes the value on unchanged), help, unit and bounds, from
which :mod:`posefix.workflow.settings` makes the stages' options and :mod:`posefix.workflow.config_schema` the
schema's sections. Lengths of unit ``d`` are relative to the reference's bounding-box diagonal; the stage scales them.
(``verify`` and ``contact`` are declared by the library's own classes: ``RepairSettings``, ``FinishSettings``,
``ContactSettings``.)
"""

from dataclasses import dataclass, field

from posefix.medial.repair import MedialRepair
from posefix.medial.skeletal_mesh import skeletal_mesh
from posefix.spacetime.classification import constraint_mask
from posefix.spacetime.constraints import spacetime_constraints
from posefix.spacetime.integration import rk45
from posefix.spacetime.keyframes import keyframes, prepare
from posefix.volumetric.repair import VolumetricRepair
from posefix.volumetric.tet_mesh import tet_mesh
from posefix.workflow.cli import library_defaults


@dataclass(frozen=True)
class KeyframesSettings:
    """Stage keyframes: the key frames from the reference to a target (S0 §4.1)."""

    count: int = field(default=library_defaults(keyframes)["count"], metadata={
        "help": "number of key frames K", "minimum": 2, "cite": "11 in S0 §4.1"})
    align: bool = field(default=library_defaults(prepare)["align"], metadata={
        "help": "remove the global rigid motion before the per-face interpolation"})
    unwrap: bool = field(default=library_defaults(prepare)["unwrap"], metadata={
        "help": "unwrap rotation branches over the face adjacency (else principal branches)"})


@dataclass(frozen=True)
class ClassifySettings:
    """Stage classify: the constrained vertices V_C (S0 §4.1)."""

    ring: int = field(default=library_defaults(constraint_mask)["ring"], metadata={
        "help": "rings removed around intersecting vertices", "minimum": 0, "cite": "1 in S0 §4.1"})
    contact: float = field(default=0.02, metadata={
        "help": "near-contact distance (0 turns it off)", "unit": "d", "minimum": 0})
    contact_radius: float = field(default=0.1, metadata={
        "help": "geodesic neighbourhood radius of a near contact", "unit": "d", "exclusiveMinimum": 0})


@dataclass(frozen=True)
class ConstraintsSettings:
    """Stage constraints: the space-time constraints of the vector field (S0 §4.1)."""

    samples: int = field(default=library_defaults(spacetime_constraints)["samples"], metadata={
        "help": "s: constraints at t_i = i/s, i = 0..s", "minimum": 2, "cite": "12 in S0 §4.1"})
    tau: float = field(default=0.3, metadata={"help": "time-axis scale", "unit": "d", "exclusiveMinimum": 0})
    tangents: str = field(default=library_defaults(spacetime_constraints)["tangents"], metadata={
        "help": "knot tangents: hermite (finite differences, the paper's) or spline (a per-vertex cubic spline)",
        "choices": ("hermite", "spline"), "cite": "S0 §4.1"})


@dataclass(frozen=True)
class IntegrateSettings:
    """Stage integrate: every reference vertex through the fitted field by RK45 (S0 §4.3)."""

    device: str = field(default="auto", metadata={
        "help": "OpenCL device type (cpu, gpu: that one or an error; auto: a GPU, else a CPU, else numpy with a "
                "warning), or the numpy backend", "choices": ("auto", "cpu", "gpu", "numpy")})
    rtol: float = field(default=library_defaults(rk45)["rtol"], metadata={
        "help": "relative tolerance per RK45 step", "exclusiveMinimum": 0})
    atol_rel: float = field(default=1e-7, metadata={
        "help": "absolute tolerance per step (1e-3 eps)", "unit": "d", "exclusiveMinimum": 0})
    h0: float = field(default=library_defaults(rk45)["h0"], metadata={
        "help": "first step size (time units)", "exclusiveMinimum": 0, "maximum": 1})
    vec: int = field(default=0, metadata={"help": "OpenCL vector width over centres (0: from the device)",
                                          "minimum": 0})


@dataclass(frozen=True)
class SkeletonSettings:
    """The reference's skeletal mesh (medial balls, S1 §2): stages skeleton and skeletal_pose."""

    medial: str = field(default=library_defaults(skeletal_mesh)["medial"], metadata={
        "help": "medial-ball centres: inner Voronoi poles (the paper's), shrinking balls, or poles with the bad ones "
                "replaced", "choices": ("poles", "shrinking_ball", "auto"), "cite": "poles: S1 §2"})
    tol: float = field(default=library_defaults(skeletal_mesh)["tol"], metadata={
        "help": "a ball crossing the surface by more than tol x its radius counts as bad", "minimum": 0,
        "maximum": 1})
    smooth_iters: int = field(default=library_defaults(skeletal_mesh)["smooth_iters"], metadata={
        "help": "iterations of the gated bi-Laplacian flow on the skeletal mesh (0: off)", "minimum": 0,
        "cite": "S1 §2"})
    smooth_step: float = field(default=library_defaults(skeletal_mesh)["smooth_step"], metadata={
        "help": "step of that flow (stable below 0.5)", "exclusiveMinimum": 0, "maximum": 0.5})


@dataclass(frozen=True)
class MedialRepairSettings:
    """The medial repair of a pose (stage repair_medial): the medial-ball flow (S1 §4) from the target."""

    margin: float = field(default=0.01, metadata={
        "help": "clearance kept between parts apart at rest", "unit": "d", "minimum": 0})
    tau: float = field(default=library_defaults(MedialRepair)["tau"], metadata={
        "help": "step size of the medial-ball flow", "exclusiveMinimum": 0, "cite": "S1 Eq. 9"})
    neighbours: int = field(default=library_defaults(MedialRepair)["neighbours"], metadata={
        "help": "candidate balls per vertex", "minimum": 1})
    max_reach: int = field(default=library_defaults(MedialRepair)["max_reach"], metadata={
        "help": "largest damaged region tried, in ball radii around the new intersections", "minimum": 1})
    max_iters: int = field(default=library_defaults(MedialRepair.repair)["max_iters"], metadata={
        "help": "flow iterations at most; it stops once no new intersection remains", "minimum": 0,
        "cite": "10-50 in S1 §4"})


@dataclass(frozen=True)
class TetMeshSettings:
    """The reference's coarse tet mesh (S4 §2.1), once per library: stage tet_mesh."""

    tet_vertices: int = field(default=library_defaults(tet_mesh)["surface_vertices"], metadata={
        "help": "surface vertices of the decimated mesh the tets are built from", "minimum": 4,
        "cite": "1.7k-3.5k tet vertices for the characters of S4 Table 3.1"})


@dataclass(frozen=True)
class VolumetricRepairSettings:
    """The volumetric repair of a pose (stage repair_volumetric): the editor fills the free region (S4 §2)."""

    iterations: int = field(default=library_defaults(VolumetricRepair.repair)["iterations"], metadata={
        "help": "volumetric editor iterations (linear solve, rotations, update) from the identity rotations",
        "minimum": 0})
    point_weight: float = field(default=library_defaults(VolumetricRepair.repair)["point_weight"], metadata={
        "help": "weight of the V_C point handles, relative to the mean diagonal of the tet Laplacian",
        "exclusiveMinimum": 0})
    max_rings: int = field(default=library_defaults(VolumetricRepair.repair)["max_rings"], metadata={
        "help": "most rings of neighbours the free region grows by (tried: 0, 1, 2, 4, ...)", "minimum": 0})
    max_free: float = field(default=library_defaults(VolumetricRepair.repair)["max_free"], metadata={
        "help": "largest free region tried, as a fraction of the vertices", "exclusiveMinimum": 0, "maximum": 1})
