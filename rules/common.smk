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
from posefix.workflow.events import failed_job_errors, recap_line, record_events
from posefix.workflow.partial_summary import finished_poses, partial_pack, partial_report, stale_files
from posefix.workflow.plan import (exclude_options, exit_on_input_error, figure_report, job_files, library,
                                   memory_limit_mb, pose_list, read_reference_vertices, repair_folders,
                                   repaired_container_files, report_targets, summary_poses)
from posefix.workflow.config_check import config_problems, folder_problems, renamed_config, typed_by_schema
from posefix.workflow.files import package_folder
from posefix.workflow.fingerprint import CodeFingerprints
from posefix.io.containers import member_digests
from posefix.workflow.locks import clear_stale_locks
from posefix.workflow.memory import memory_problem, stage_memory_mb
from posefix.workflow.resources import available_memory, device_problems
from posefix.report.contents import COMPARED_REPAIRS, POSE_FIGURES, TIMED_STAGES, VIEWER_FILES


SCHEMA = yaml.safe_load((Path(workflow.basedir) / "schemas" / "config.schema.yaml").read_text())
_renamed, _notices = renamed_config(config)  # the keys renamed in 2026-12, read for one release
config.clear()
config.update(_renamed)
for _notice in _notices if workflow.is_main_process else ():
    print(_notice, file=sys.stderr)
config.update(typed_by_schema(dict(config), SCHEMA))  # --config leaves text inside nested values
_problems = config_problems(config, SCHEMA)
if _problems:  # one line per problem, naming the key; no schema dump
    sys.exit("\n".join(f"posefix: error: config: {p}" for p in _problems))
validate(config, "../schemas/config.schema.yaml")  # fills in the schema's defaults

EVENTS = record_events()  # Snakemake's events of this run: the failed jobs' logs for onerror

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


def log_file(job, wildcard="pose", folder=None):
    """The log file of a rule's job in ``folder`` (the library's results by default): posefix.workflow.plan.job_files."""
    return job_files(folder or RESULTS, job, wildcard)[0]


def benchmark_file(job, wildcard="pose", folder=None):
    """The benchmark file of a rule's job (:func:`log_file`'s twin)."""
    return job_files(folder or RESULTS, job, wildcard)[1]


def _library(wanted):
    """The pose library, its poses ``wanted`` (all: None); a problem with its files ends the run in one line."""
    with exit_on_input_error():
        return library(config, wanted)


LIBRARY = _library(pose_list(config["poses"]))
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
REPAIRS = config["repairs"]  # the repairs run beside space-time, compared in the report
REPAIR_CHOICES = COMPARED_REPAIRS  # stage repair_<name> writes results/<library>/<pose>/<name>.h5


# Memory this run may use (MB): the user's --resources mem_mb; in a local run without it, the memory available now,
# registered as the run's mem_mb so that Snakemake never starts jobs together that would not fit (each rule asks for
# memory_mb() of its stage); 0 (no limit) on a cluster, where each job gets its own.
_GIVEN_MB = getattr(workflow.global_resources.get("mem_mb"), "value", None)
MEMORY_LIMIT_MB = memory_limit_mb(_GIVEN_MB, workflow.local_exec, available_memory() / 1e6)
if _GIVEN_MB is None and workflow.local_exec:
    workflow.register_resource("mem_mb", MEMORY_LIMIT_MB)


_VERTICES = {}


def reference_vertices():
    """The reference's vertex count, read once it can be (0 until then: plan.read_reference_vertices)."""
    if "n" not in _VERTICES:
        _VERTICES.update(read_reference_vertices(RESULTS, LIBRARY))
    return _VERTICES.get("n", 0)


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


def repair_artifacts(pose):
    """The artifacts of the other repairs of ``pose``: {name: results/<library>/<pose>/<name>.h5}."""
    return {name: f"{RESULTS}/{pose}/{name}.h5" for name in REPAIRS}


def other_repaired_file(name, pose):
    """Output path of another repair's repaired mesh: results/<library>/repaired-<name>/<pose><input suffix>."""
    return f"{RESULTS}/repaired-{name}/{pose}{WHOLE_LIBRARY.pose(pose).suffix}"


def pose_file(wildcards):
    """Mesh file of the target pose ``wildcards.pose``."""
    return LIBRARY.pose(wildcards.pose).path


def library_files():
    """Reference and target mesh files, in manifest order."""
    return [LIBRARY.reference.path] + [p.path for p in LIBRARY.poses]


def exclude_args(wildcards):
    """Command-line options of classify for the hand-picked exclusions of a pose."""
    return exclude_options(config["classify"]["exclude"].get(wildcards.pose))


def exclude_files(wildcards):
    """Input files of classify: the exclusion file of a pose, if one is configured."""
    value = config["classify"]["exclude"].get(wildcards.pose)
    return [value] if isinstance(value, str) else []


def repaired_file(pose):
    """Output path of the repaired mesh of a pose: results/<library>/repaired/<pose><input suffix>."""
    return f"{RESULTS}/repaired/{pose}{WHOLE_LIBRARY.pose(pose).suffix}"


def pose_figure(figure):
    """The report() output of one figure of stage render (wildcard {pose}), caption rules/captions/<figure>.rst."""
    return report(**figure_report(REPORTS, figure, POSE_FIGURES[figure]))


def _out_of_date(required):
    """The files of ``required`` (dict: pose -> paths) that this code and these inputs would make again (set)."""
    return stale_files(workflow.main_snakefile, config | {"poses": list(required)},
                       [p for paths in required.values() for p in paths])


def summary_inputs(pose):
    """The files of ``pose`` that the library's summary reads (the pose has finished when they all exist)."""
    return ([f"{RESULTS}/{pose}/{a}.h5" for a in ("keyframes", "classify", "verify", "downstream")]
            + list(repair_artifacts(pose).values()) + [repaired_file(pose)])


def _earlier_finished():
    """The poses outside this run's that an earlier run finished and that are still up to date (the summary's)."""
    earlier = {p.name: summary_inputs(p.name) for p in WHOLE_LIBRARY.poses if p.name not in POSES}
    return finished_poses(earlier, _out_of_date(earlier) if workflow.is_main_process else set())[0]


SUMMARY_POSES = summary_poses(config["poses"] and POSES, [p.name for p in WHOLE_LIBRARY.poses],
                              _earlier_finished() if config["poses"] else ())


def repaired_containers():
    """For a container library: each repair's file, results/<library>/repaired[-<repair>]/<file name> (rule pack)."""
    return repaired_container_files(RESULTS, LIBRARY.container, REPAIRS)


def get_final_output():
    """The targets: each repair's mesh of every pose (and container file), and the report (plan.report_targets)."""
    meshes = [repaired_file(p) for p in POSES] + [other_repaired_file(b, p) for b in REPAIRS for p in POSES]
    return [*meshes, *repaired_containers(), *report_targets(REPORTS, POSES, list(POSE_FIGURES))]


def _finished(required):
    """``(finished, unfinished)`` poses of ``required`` (pose -> files): all there, none out of date."""
    return finished_poses(required, _out_of_date(required))


def partial_summary(errors):
    """After a failed run: the report of the poses that finished, the others listed with their error line."""
    poses = _finished({p: summary_inputs(p) for p in SUMMARY_POSES})
    partial_report(stage_script, (RESULTS, REPORTS), poses, errors, (REPAIRS, config["summary"]["distortion_limit"]))


def container_flags():
    """``--container <file>`` and ``--mesh <prim>`` of the library's container for stages unpack and pack."""
    return f"--container {shlex.quote(LIBRARY.container)} --mesh {shlex.quote(LIBRARY.mesh)}"


def partial_containers():
    """After a failed run of a container library: each repair's file, with the poses that finished repaired."""
    for folder in repair_folders(RESULTS, REPAIRS) if LIBRARY.container else ():
        done = _finished({p: [f"{folder}/{p}.ply"] for p in SUMMARY_POSES})[0]
        partial_pack(stage_script("pack"), LIBRARY, folder, done, len(SUMMARY_POSES))
