# Helpers of the rules: config validation, the pose library, paths, get_final_output(). No rules here.
# posefix is installed in the interpreter that runs Snakemake (the venv's under `make run`).
import os
import shlex
import sys
from pathlib import Path

import yaml
from snakemake.utils import validate

from posefix.workflow import demo
from posefix.workflow.cli import config_flags, named_options, put_interpreter_first_on_path
from posefix.workflow.command import failed_job_errors, recap_line
from posefix.workflow.partial_summary import finished_poses, pose_errors, stage_finished, stale_files
from posefix.workflow.config_check import config_problems, folder_problems, typed_by_schema
from posefix.io.errors import InputError
from posefix.workflow.files import package_folder
from posefix.workflow.fingerprint import CodeFingerprints
from posefix.io.artifacts import read_artifact
from posefix.io.containers import container_format, container_stem, member_digests, open_container
from posefix.io.library import Library, container_library, discover_library, read_reference
from posefix.workflow.locks import clear_stale_locks
from posefix.workflow.memory import memory_problem, stage_memory_mb
from posefix.workflow.resources import available_memory, device_problems
from posefix.io.meshes import mesh_file
from posefix.report.contents import POSE_FIGURES, TIMED_STAGES, VIEWER_FILES


SCHEMA = yaml.safe_load((Path(workflow.basedir) / "schemas" / "config.schema.yaml").read_text())
config.update(typed_by_schema(dict(config), SCHEMA))  # --config leaves text inside nested values
_problems = config_problems(config, SCHEMA)
if _problems:  # one line per problem, naming the key; no schema dump
    sys.exit("\n".join(f"posefix: error: config: {p}" for p in _problems))
validate(config, "../schemas/config.schema.yaml")  # fills in the schema's defaults

if workflow.is_main_process:  # not in the jobs a cluster executor starts: they cannot see the main process
    _stale = clear_stale_locks(".")
    if _stale:
        print(f"posefix: removed {len(_stale)} stale Snakemake lock(s) of an interrupted run in {Path.cwd()} "
              "(no other Snakemake runs there)", file=sys.stderr)

# The rules call `python`: a conda environment's under --sdm conda (envs/posefix.yaml), else the interpreter that
# runs Snakemake (the venv's under `make run` and `posefix repair`), first on the PATH of every job.
put_interpreter_first_on_path()
# Alembic caches are read and written by Blender (posefix.io.formats.alembic): the checkout's bpy environment (make
# test makes it) unless POSEFIX_BLENDER names another Python with bpy, or Blender.
if (Path(workflow.basedir) / ".venv-blender" / "bin" / "python").is_file():
    os.environ.setdefault("POSEFIX_BLENDER", str(Path(workflow.basedir) / ".venv-blender" / "bin" / "python"))


VIEWER_PAGE = [str(package_folder() / "report" / f) for f in VIEWER_FILES.values()]
"""The files of the 3D viewer page (template, script, vendored three.js), inputs of rule viewer."""


def stage_script(name):
    """Absolute path of ``stages/<name>.py`` (rules work from any --directory)."""
    return str(Path(workflow.basedir) / "stages" / f"{name}.py")


RENAMED_RULES = {"author": "skeletal_pose", "author_volumetric": "volumetric_pose",
                 "animate_volumetric": "volumetric_animate"}
"""Rules renamed in 2026-12 (old name: new name, so that a rule, its script and its config section share one name);
the old names stay as aliases for one release and say so."""


onstart:
    for _old in sorted(RENAMED_RULES.keys() & set(workflow.dag_settings.targets)):
        print(f"posefix: rule '{_old}' is now '{RENAMED_RULES[_old]}' (the old name goes in the next release)",
              file=sys.stderr)
    _absent = device_problems(config) if workflow.local_exec else ()  # known only now: local, or on a cluster
    if _absent:  # before any job: the stage would fail each pose's integrate in turn
        sys.exit("\n".join(f"posefix: error: config: {p}" for p in _absent))


CODE = CodeFingerprints(package_folder().parent, cache=Path(".snakemake") / "posefix-code.json")


def intermediate(path):
    """``path`` as Snakemake's ``temp()`` unless config ``keep_intermediates``: an artifact only a next stage reads."""
    return path if config["keep_intermediates"] else temp(path)


def stage_code(name):
    """Fingerprint of ``stages/<name>.py`` and the posefix modules it imports (a param of its rule: changed
    code reruns the stage and what depends on it, and nothing else). Each file is read once per run; the jobs
    find the run's fingerprints in .snakemake/posefix-code.json (the Snakefile saves it)."""
    return CODE.fingerprint(stage_script(name))


def _pose_list(value):
    """config['poses'] as a list (it may be given as 'a,b' on the command line)."""
    if isinstance(value, str):
        return [p.strip() for p in value.split(",") if p.strip()]
    return value or None


def _demo_library(wanted):
    folder = config["demo"]["folder"]
    reference = mesh_file(f"{folder}/{demo.REFERENCE_NAME}{demo.REFERENCE_SUFFIX}")
    poses = [mesh_file(f"{folder}/{p.name}{p.suffix}") for p in demo.POSES]
    if wanted:
        unknown = sorted(set(wanted) - {p.name for p in poses})
        if unknown:
            raise InputError(folder, f"pose(s) not in the demo library: {', '.join(unknown)}")
        poses = [p for p in poses if p.name in wanted]
    return Library(folder=folder, name=config["name"] or "demo", reference=reference, poses=tuple(poses))


def _library(wanted):
    """The pose library, its poses ``wanted`` (all: None); input problems end the run with one line."""
    try:
        if config["library"] is None:
            return _demo_library(wanted)
        reference = None if config["reference"] is None else str(config["reference"])  # a frame: 12
        if container_format(config["library"]):  # one USD or glTF file: its poses unpacked under results/
            name = config["name"] or container_stem(config["library"])
            return container_library(config["library"], f"{config['results']}/{name}/poses", reference=reference,
                                     poses=wanted, name=name, mesh=config["mesh"])
        return discover_library(config["library"], reference=reference, poses=wanted, name=config["name"])
    except InputError as exc:
        sys.exit(f"posefix: error: {exc}")


LIBRARY = _library(_pose_list(config["poses"]))
WHOLE_LIBRARY = _library(None) if config["poses"] else LIBRARY  # every pose of the folder (the summary's)
POSES = [p.name for p in LIBRARY.poses]
for _path, _cause in LIBRARY.refused if workflow.is_main_process else ():  # one line each; the others go on
    print(f"posefix: warning: {_path}: {_cause}; left out of the library", file=sys.stderr)
_unknown = sorted(set(config["classify"]["exclude"]) - set(POSES))
if _unknown:
    sys.exit(f"posefix: error: classify.exclude names pose(s) not in the library: {', '.join(_unknown)}")
RESULTS = f"{config['results']}/{LIBRARY.name}"
REPORTS = f"{config['reports']}/{LIBRARY.name}"
_unwritable = folder_problems(config, LIBRARY.name) if workflow.is_main_process else ()
if _unwritable:  # before anything runs (Snakemake itself would stop where the first file is written there)
    sys.exit("\n".join(f"posefix: error: config: {p}" for p in _unwritable))
IS_DEMO = config["library"] is None
BASELINES = config["baselines"]  # repairs beside S0, compared in the report
BASELINE_CHOICES = ("medial", "volumetric", "contact")  # stage repair_<name> writes results/<library>/<pose>/<name>.h5


def _memory_limit_mb():
    """Memory this run may use (MB): the user's ``--resources mem_mb``; in a local run without it, the memory
    available now, registered as the run's mem_mb so that Snakemake never starts jobs together that would not fit
    (each rule asks for memory_mb() of its stage); 0 (no limit) on a cluster, where each job gets its own."""
    given = workflow.global_resources.get("mem_mb")
    if given is not None and given.value is not None:
        return int(given.value)
    if not workflow.local_exec:
        return 0
    limit = int(available_memory() / 1e6)
    workflow.register_resource("mem_mb", limit)
    return limit


MEMORY_LIMIT_MB = _memory_limit_mb()


_VERTICES = {}


def reference_vertices():
    """Vertex count of the reference: from reference.h5 when validate_reference wrote it from this file, else from
    the mesh file, or the USD or glTF file before it is unpacked (0 while it cannot be read: the demo's files not
    yet written, or a bad file that validate_reference names)."""
    if "n" not in _VERTICES:
        checked = Path(f"{RESULTS}/reference.h5")
        try:
            if checked.is_file() and checked.stat().st_mtime >= Path(LIBRARY.reference.path).stat().st_mtime:
                _VERTICES["n"] = int(read_artifact(f"{RESULTS}/reference.h5", "validate", [])[1]["metrics"]["vertices"])
            elif LIBRARY.container and not Path(LIBRARY.reference.path).is_file():  # not yet unpacked
                _VERTICES["n"] = open_container(LIBRARY.container, LIBRARY.mesh).n
            else:
                _VERTICES["n"] = len(read_reference(LIBRARY.reference.path)[0])
        except InputError as exc:  # a reference mesh file that is there and cannot be read: refused before any job
            reference = Path(LIBRARY.reference.path)
            _VERTICES["error"] = exc if Path(exc.path) == reference and reference.is_file() else None
            return 0
        except Exception:  # noqa: BLE001  (any other unreadable file: validate_reference names it)
            return 0
    return _VERTICES["n"]


if workflow.is_main_process:  # an unreadable reference, or one too large for the run, is refused before any job
    _problem = memory_problem(reference_vertices(), MEMORY_LIMIT_MB)
    if _VERTICES.get("error"):
        sys.exit(f"posefix: error: {_VERTICES['error']}")
    if _problem:
        sys.exit(f"posefix: error: {LIBRARY.reference.path}: {_problem}")


def within_limit(mb):
    """``mb`` capped at what the run may use (Snakemake refuses a job that asks for more than the run has)."""
    return min(mb, MEMORY_LIMIT_MB) if MEMORY_LIMIT_MB > 0 else mb


def memory_mb(stage):
    """``resources.mem_mb`` of the stage's rule (a function of the job), its measured need for the reference's
    size (posefix.workflow.resources.stage_memory_mb) within the run's limit (a reference that needs more is refused
    when the run starts, in one line)."""
    return lambda wildcards: within_limit(stage_memory_mb(stage, reference_vertices()))


def baseline_artifacts(pose):
    """The artifacts of the baseline repairs of ``pose``: {name: results/<library>/<pose>/<name>.h5}."""
    return {name: f"{RESULTS}/{pose}/{name}.h5" for name in BASELINES}


def baseline_repaired_file(name, pose):
    """Output path of a baseline's repaired mesh: results/<library>/repaired-<name>/<pose><input suffix>."""
    return f"{RESULTS}/repaired-{name}/{pose}{WHOLE_LIBRARY.pose(pose).suffix}"


def pose_file(wildcards):
    """Mesh file of the target pose ``wildcards.pose``."""
    return LIBRARY.pose(wildcards.pose).path


def library_files():
    """Reference and target mesh files, in manifest order."""
    return [LIBRARY.reference.path] + [p.path for p in LIBRARY.poses]


def exclude_args(wildcards):
    """Command-line options of classify for the hand-picked exclusions of a pose."""
    value = config["classify"]["exclude"].get(wildcards.pose)
    if value is None:
        return ""
    if isinstance(value, str):
        return f"--exclude-file {shlex.quote(value)}"
    return "--exclude " + ",".join(str(int(i)) for i in value)


def exclude_files(wildcards):
    """Input files of classify: the exclusion file of a pose, if one is configured."""
    value = config["classify"]["exclude"].get(wildcards.pose)
    return [value] if isinstance(value, str) else []


def repaired_file(pose):
    """Output path of the repaired mesh of a pose: results/<library>/repaired/<pose><input suffix>."""
    return f"{RESULTS}/repaired/{pose}{WHOLE_LIBRARY.pose(pose).suffix}"


def pose_figure(figure):
    """The report() output of one figure of stage render (wildcard {pose}), caption rules/captions/<figure>.rst."""
    return report(
        f"{REPORTS}/figures/{{pose}}/{figure}.png",
        caption=f"captions/{figure}.rst",
        category="2. Poses",
        subcategory="{pose}",
        labels={"pose": "{pose}", "figure": POSE_FIGURES[figure]},
    )


def _out_of_date(required):
    """The files of ``required`` (dict: pose -> paths) that this code and these inputs would make again (set)."""
    return stale_files(workflow.main_snakefile, config | {"poses": list(required)},
                       [p for paths in required.values() for p in paths])


def summary_inputs(pose):
    """The files of ``pose`` that the library's summary reads (the pose has finished when they all exist)."""
    return ([f"{RESULTS}/{pose}/{a}.h5" for a in ("keyframes", "classify", "verify", "downstream")]
            + list(baseline_artifacts(pose).values()) + [repaired_file(pose)])


def _summary_poses():
    """The poses of the library's summary, in library order: this run's, and those of the folder that an earlier
    run finished and that are still up to date (a repair of some poses adds them to the summary rather than replacing
    it; those are read as they are, not rerun)."""
    if not config["poses"]:
        return POSES
    earlier = {p.name: summary_inputs(p.name) for p in WHOLE_LIBRARY.poses if p.name not in POSES}
    finished, _ = finished_poses(earlier, _out_of_date(earlier) if workflow.is_main_process else set())
    return [p.name for p in WHOLE_LIBRARY.poses if p.name in POSES or p.name in finished]


SUMMARY_POSES = _summary_poses()


def repaired_containers():
    """For a USD or glTF library: the container of each repair, results/<library>/repaired[-<baseline>]/<file name>
    (rule pack); else none."""
    if not LIBRARY.container:
        return []
    name = os.path.basename(LIBRARY.container)
    return [f"{RESULTS}/repaired/{name}", *[f"{RESULTS}/repaired-{b}/{name}" for b in BASELINES]]


def get_final_output():
    """The targets of the workflow: every repaired pose (and, for a USD or glTF library, the file of each repair),
    the report figures, the summary, the overview and the 3D viewer."""
    return [
        *[repaired_file(p) for p in POSES],
        *[baseline_repaired_file(b, p) for b in BASELINES for p in POSES],
        *repaired_containers(),
        *expand(f"{REPORTS}/figures/{{pose}}/{{figure}}.png", pose=POSES, figure=list(POSE_FIGURES)),
        *expand(f"{REPORTS}/figures/{{pose}}/downstream.png", pose=POSES),
        f"{REPORTS}/summary.json",
        f"{REPORTS}/overview.png",
        f"{REPORTS}/viewer.html",
    ]


def partial_summary(errors):
    """After a failed run: the summary, overview and 3D viewer of the poses that finished, the others listed with
    their error line (``errors``: the posefix error lines of the failed jobs); nothing when no pose finished."""
    required = {p: summary_inputs(p) for p in SUMMARY_POSES}
    finished, unfinished = finished_poses(required, _out_of_date(required))
    if not finished or not unfinished:
        return
    failed = [f"--failed={pose}={line}" for pose, line in pose_errors(unfinished, errors).items()]
    summary = [sys.executable, stage_script("summary"), "--results", RESULTS, "--poses", ",".join(finished),
               "--baselines", ",".join(BASELINES), "--distortion-limit", str(config["summary"]["distortion_limit"]),
               *failed, "--out", f"{REPORTS}/summary.json", "--markdown", f"{REPORTS}/summary.md",
               "--log", f"{RESULTS}/logs/partial-summary.log"]
    overview = [sys.executable, stage_script("overview"), "--summary", f"{REPORTS}/summary.json",
                "--png", f"{REPORTS}/overview.png", "--html", f"{REPORTS}/summary.html",
                "--log", f"{RESULTS}/logs/partial-overview.log"]
    viewer = [sys.executable, stage_script("viewer"), "--summary", f"{REPORTS}/summary.json", "--results", RESULTS,
              "--out", f"{REPORTS}/viewer.html", "--log", f"{RESULTS}/logs/partial-viewer.log"]
    if all(stage_finished(stage) for stage in (summary, overview, viewer)):
        print(f"posefix: summary of the {len(finished)} poses that finished, {len(unfinished)} listed as failed: "
              f"{REPORTS}/summary.html", file=sys.stderr)


def container_flags():
    """``--container <file>`` and ``--mesh <prim>`` of the library's container for stages unpack and pack."""
    return f"--container {shlex.quote(LIBRARY.container)} --mesh {shlex.quote(LIBRARY.mesh)}"


def partial_containers():
    """After a failed run of a USD or glTF library: the file of each repair with the poses that finished repaired
    and the others as in the input (stage pack), so that one bad pose does not hold back the others."""
    for repair in ["repaired", *[f"repaired-{b}" for b in BASELINES]] if LIBRARY.container else ():
        required = {p: [f"{RESULTS}/{repair}/{p}.ply"] for p in SUMMARY_POSES}
        done, _ = finished_poses(required, _out_of_date(required))
        out = f"{RESULTS}/{repair}/{os.path.basename(LIBRARY.container)}"
        if not done or len(done) == len(SUMMARY_POSES):
            continue
        command = [sys.executable, stage_script("pack"), "--container", LIBRARY.container, "--mesh", LIBRARY.mesh,
                   "--repaired", f"{RESULTS}/{repair}", "--poses", ",".join(done), "--out", out,
                   "--log", f"{RESULTS}/logs/partial-pack-{repair}.log"]
        if stage_finished(command):
            print(f"posefix: {out}: {len(done)} of {len(SUMMARY_POSES)} poses repaired, the others as in the input",
                  file=sys.stderr)
