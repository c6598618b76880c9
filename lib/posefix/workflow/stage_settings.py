"""The stages' settings, declared once where no library settings class holds them (config sections ``keyframes``,
``classify``, ``constraints``, ``fit``, ``integrate``, ``downstream``, ``summary``, ``demo``, ``medial.*``,
``volumetric.*``): each field's default, help, unit and bounds, from which :mod:`posefix.workflow.settings` makes the
stages' options and :mod:`posefix.workflow.config_schema` the schema's sections. A default that a library function
also has (the stage passes the value on unchanged) is written here as a number, and ``tests/test_defaults.py`` checks
that the two agree: importing the library here would cost every stage the imports of every method (0.2 s a stage). Lengths of unit ``d`` are relative to the reference's bounding-box diagonal; the stage scales them.
(``verify`` and ``contact`` are declared by the library's own classes: ``RepairSettings``, ``FinishSettings``,
``ContactSettings``.)
"""

from dataclasses import dataclass, field


@dataclass(frozen=True)
class KeyframesSettings:
    """Stage keyframes: the key frames from the reference to a target (S0 §4.1)."""

    count: int = field(default=11, metadata={
        "help": "number of key frames K", "minimum": 2, "cite": "11 in S0 §4.1"})
    align: bool = field(default=True, metadata={
        "help": "remove the global rigid motion before the per-face interpolation"})
    unwrap: bool = field(default=True, metadata={
        "help": "unwrap rotation branches over the face adjacency (else principal branches)"})


@dataclass(frozen=True)
class ClassifySettings:
    """Stage classify: the constrained vertices V_C (S0 §4.1)."""

    ring: int = field(default=1, metadata={
        "help": "rings removed around intersecting vertices", "minimum": 0, "cite": "1 in S0 §4.1"})
    contact: float = field(default=0.02, metadata={
        "help": "near-contact distance (0 turns it off)", "unit": "d", "minimum": 0})
    contact_radius: float = field(default=0.1, metadata={
        "help": "geodesic neighbourhood radius of a near contact", "unit": "d", "exclusiveMinimum": 0})


@dataclass(frozen=True)
class ConstraintsSettings:
    """Stage constraints: the space-time constraints of the vector field (S0 §4.1)."""

    samples: int = field(default=12, metadata={
        "help": "s: constraints at t_i = i/s, i = 0..s", "minimum": 2, "cite": "12 in S0 §4.1"})
    tau: float = field(default=0.3, metadata={"help": "time-axis scale", "unit": "d", "exclusiveMinimum": 0})
    tangents: str = field(default='spline', metadata={
        "help": "knot tangents: hermite (finite differences, the paper's) or spline (a per-vertex cubic spline)",
        "choices": ("hermite", "spline"), "cite": "S0 §4.1"})


@dataclass(frozen=True)
class FitOptions:
    """Stage fit: the greedy RBF fit of the space-time vector field (S0 §4.2); relative lengths where the library's
    :class:`~posefix.spacetime.fit.FitSettings` takes lengths, and its memory in GB."""

    eps_rel: float = field(default=0.0001, metadata={
        "help": "stop at max error < eps_rel * bbox diagonal", "minimum": 0, "cite": "1e-4 in S0 §4.2"})
    eps_rms_rel: float = field(default=0.0, metadata={
        "help": "stop at rms error < this * bbox diagonal (0: off)", "minimum": 0})
    max_centers: int = field(default=4000, metadata={
        "help": "stop at this many centres", "minimum": 16})
    candidates: int = field(default=1024, metadata={
        "help": "p: worst constraints considered per iteration", "minimum": 1, "cite": "1024 in S0 §4.2"})
    batch: int = field(default=128, metadata={
        "help": "m: centres added per iteration", "minimum": 1, "cite": "128 in S0 §4.2"})
    selection: str = field(default='fps', metadata={
        "help": "centre selection: fps (farthest points within the candidates, the paper's) or worst (the m worst, "
                "Carr et al.)",
        "choices": ("fps", "worst"), "cite": "S0 §4.2"})
    update: str = field(default='blocked', metadata={
        "help": "blocked Cholesky updates or full LU refactorization every iteration", "choices": ("blocked", "full")})
    memory_gb: float = field(default=8.0, metadata={
        "help": "budget of the kernel cache (GB); lowered to what --mem-mb and the machine allow",
        "exclusiveMinimum": 0})
    device: str = field(default='auto', metadata={
        "help": "where the residual is recomputed when the kernel cache does not fit: an OpenCL device (cpu, gpu: "
                "that one or an error; auto: a GPU, else a CPU, else numpy) or numpy",
        "choices": ("auto", "cpu", "gpu", "numpy")})
    keep_checkpoint: bool = field(default=False, metadata={
        "help": "keep the checkpoint once the fit is written: a rerun with another --eps-rel or --max-centers "
                "continues from it (else it starts over; 64 MB per lion pose)"})


@dataclass(frozen=True)
class IntegrateSettings:
    """Stage integrate: every reference vertex through the fitted field by RK45 (S0 §4.3)."""

    device: str = field(default='auto', metadata={
        "help": "OpenCL device type (cpu, gpu: that one or an error; auto: a GPU, else a CPU, else numpy with a "
                "warning), or the numpy backend", "choices": ("auto", "cpu", "gpu", "numpy")})
    rtol: float = field(default=1e-09, metadata={
        "help": "relative tolerance per RK45 step", "exclusiveMinimum": 0})
    atol_rel: float = field(default=1e-07, metadata={
        "help": "absolute tolerance per step (1e-3 eps)", "unit": "d", "exclusiveMinimum": 0})
    h0: float = field(default=0.05, metadata={
        "help": "first step size (time units)", "exclusiveMinimum": 0, "maximum": 1})
    vec: int = field(default=0, metadata={"help": "OpenCL vector width over centres (0: from the device)",
                                          "minimum": 0})


@dataclass(frozen=True)
class SkeletonSettings:
    """The reference's skeletal mesh (medial balls, S1 §2): stages skeleton and skeletal_pose."""

    medial: str = field(default='auto', metadata={
        "help": "medial-ball centres: inner Voronoi poles (the paper's), shrinking balls, or poles with the bad ones "
                "replaced", "choices": ("poles", "shrinking_ball", "auto"), "cite": "poles: S1 §2"})
    tol: float = field(default=0.5, metadata={
        "help": "a ball crossing the surface by more than tol x its radius counts as bad", "minimum": 0,
        "maximum": 1})
    smooth_iters: int = field(default=10, metadata={
        "help": "iterations of the gated bi-Laplacian flow on the skeletal mesh (0: off)", "minimum": 0,
        "cite": "S1 §2"})
    smooth_step: float = field(default=0.1, metadata={
        "help": "step of that flow (stable below 0.5)", "exclusiveMinimum": 0, "maximum": 0.5})


@dataclass(frozen=True)
class MedialRepairSettings:
    """The medial repair of a pose (stage repair_medial): the medial-ball flow (S1 §4) from the target."""

    margin: float = field(default=0.01, metadata={
        "help": "clearance kept between parts apart at rest", "unit": "d", "minimum": 0})
    tau: float = field(default=0.5, metadata={
        "help": "step size of the medial-ball flow", "exclusiveMinimum": 0, "cite": "S1 Eq. 9"})
    neighbours: int = field(default=64, metadata={
        "help": "candidate balls per vertex", "minimum": 1})
    max_reach: int = field(default=4, metadata={
        "help": "largest damaged region tried, in ball radii around the new intersections", "minimum": 1})
    max_iters: int = field(default=50, metadata={
        "help": "flow iterations at most; it stops once no new intersection remains", "minimum": 0,
        "cite": "10-50 in S1 §4"})


@dataclass(frozen=True)
class TetMeshSettings:
    """The reference's coarse tet mesh (S4 §2.1), once per library: stage tet_mesh."""

    tet_vertices: int = field(default=2500, metadata={
        "help": "surface vertices of the decimated mesh the tets are built from", "minimum": 4,
        "cite": "1.7k-3.5k tet vertices for the characters of S4 Table 3.1"})


@dataclass(frozen=True)
class VolumetricRepairSettings:
    """The volumetric repair of a pose (stage repair_volumetric): the editor fills the free region (S4 §2)."""

    iterations: int = field(default=10, metadata={
        "help": "volumetric editor iterations (linear solve, rotations, update) from the identity rotations",
        "minimum": 0})
    point_weight: float = field(default=10.0, metadata={
        "help": "weight of the V_C point handles, relative to the mean diagonal of the tet Laplacian",
        "exclusiveMinimum": 0})
    max_rings: int = field(default=16, metadata={
        "help": "most rings of neighbours the free region grows by (tried: 0, 1, 2, 4, ...)", "minimum": 0})
    max_free: float = field(default=0.5, metadata={
        "help": "largest free region tried, as a fraction of the vertices", "exclusiveMinimum": 0, "maximum": 1})


@dataclass(frozen=True)
class SkeletalPoseSettings:
    """Stage skeletal_pose: a pose library authored from a rig (S1 §2-4), besides its skeletal mesh's settings."""

    falloff: float = field(default=0.2, metadata={
        "help": "skinning blend length / mean bone length", "exclusiveMinimum": 0})
    min_sine: float = field(default=0.05, metadata={
        "help": "skeletal triangles with a smaller corner sine use the rig's rotation as frame", "minimum": 0,
        "maximum": 1})
    min_area: float = field(default=0.1, metadata={
        "help": "so do skeletal triangles smaller than this x their mesh triangle (a collapsed skeleton)",
        "minimum": 0})
    tau: float = field(default=0.5, metadata={
        "help": "step size of the medial-ball flow", "exclusiveMinimum": 0, "cite": "S1 Eq. 9"})
    margin: float = field(default=0.01, metadata={
        "help": "flow margin between parts apart at rest (0: the paper's flow, no margin)", "unit": "d",
        "minimum": 0})
    neighbours: int = field(default=64, metadata={
        "help": "candidate balls per vertex at most in the flow (0: all within R_i, as the paper)", "minimum": 0,
        "cite": "S1 Eq. 10"})
    max_iters: int = field(default=50, metadata={
        "help": "flow iterations at most", "minimum": 0, "cite": "10-50 needed in S1 §4"})


@dataclass(frozen=True)
class VolumetricPoseSettings:
    """Stage volumetric_pose: a pose library authored from a pose script (S4 §2), besides its tet mesh's settings."""

    iterations: int = field(default=10, metadata={
        "help": "volumetric editor iterations per frame (linear solve, rotations, update)", "minimum": 0})
    frames: int = field(default=4, metadata={
        "help": "frames a pose is reached in, each warm-started from the last", "minimum": 1})


@dataclass(frozen=True)
class VolumetricAnimateSettings:
    """Stage volumetric_animate: the reference animated by marker tracks (S4 §3.2), besides its tet mesh's settings."""

    attach: str = field(default='position', metadata={
        "help": "markers at their first-frame positions, or at the reference vertices their labels name",
        "choices": ("position", "vertex")})
    max_offset: float = field(default=0.05, metadata={
        "help": "with --attach position: largest distance of a first-frame marker from the reference surface",
        "unit": "d", "minimum": 0})
    iterations: int = field(default=3, metadata={
        "help": "volumetric editor iterations per frame, warm-started from the previous frame", "minimum": 0,
        "cite": "2-3 in S4 §3.2"})
    first_iterations: int = field(default=10, metadata={
        "help": "volumetric editor iterations of the first frame, from the rest pose's rotations", "minimum": 0})


@dataclass(frozen=True)
class DownstreamSettings:
    """Stage downstream: Gauss-Newton discrete shells toward the original and the repaired pose (S0 §5), over the
    grid of ``alphas`` x ``k_bend``."""

    alphas: tuple = field(default=(1.0,), metadata={
        "help": "interpolation weights of the example, e.g. 0.5,1.0", "items": float, "minItems": 1,
        "item_bounds": {"exclusiveMinimum": 0, "maximum": 1}})
    k_bend: tuple = field(default=(0.01,), metadata={
        "help": "bending stiffnesses k_b of the grid (one setting by default)", "items": float, "minItems": 1,
        "item_bounds": {"exclusiveMinimum": 0}})
    k_stretch: float = field(default=1.0, metadata={
        "help": "stretching stiffness k_l", "exclusiveMinimum": 0})
    max_iters: int = field(default=200, metadata={
        "help": "Gauss-Newton iterations at most", "minimum": 1})
    rel_tol: float = field(default=1e-06, metadata={
        "help": "stop when the relative decrease of the energy falls below this", "minimum": 0})
    stall_iters: int = field(default=10, metadata={
        "help": "stop as stalled after this many accepted steps below 1e-3 in a row",
        "minimum": 1})


@dataclass(frozen=True)
class SummarySettings:
    """Stages summary and render: when a repaired face counts as distorted."""

    distortion_limit: float = field(default=4.0, metadata={
        "help": "a face whose edge-length or area ratio (or its inverse) exceeds this against both the target and the "
                "reference is distorted; a pose with more than 0.1 % of its faces so, or one beyond 10x, is 'check'",
        "exclusiveMinimum": 1})


@dataclass(frozen=True)
class DemoSettings:
    """Stage demo: the built-in demo library (a bumpy capsule bent into four poses)."""

    seed: int = field(default=7, metadata={
        "help": "seed of the demo limb's bump pattern"})
    around: int = field(default=40, metadata={
        "help": "vertices per ring of the demo capsule", "minimum": 8})
