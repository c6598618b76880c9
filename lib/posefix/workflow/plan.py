"""The run's plan in plain Python, for rules/common.smk: the pose library the config names, the reference's size (the
memory check), classify's exclusions, the poses of the summary, the containers and the targets of the workflow.

Functions of their arguments only (the config, paths, the library): the ``.smk`` files call them and only declare
rules (issue 51).
"""

import os
import shlex
import sys
from contextlib import contextmanager
from pathlib import Path

from posefix.io.artifacts import read_artifact
from posefix.io.containers import container_format, container_stem, open_container
from posefix.io.errors import InputError
from posefix.io.library import Library, container_library, discover_library, read_reference
from posefix.io.meshes import mesh_file
from posefix.workflow import demo


def pose_list(value):
    """config ``poses`` as a list of names, None for every pose (it may come as ``a,b`` on the command line).

    Examples
    --------
    >>> pose_list("lion-01, lion-02"), pose_list(["a"]), pose_list(None)
    (['lion-01', 'lion-02'], ['a'], None)
    """
    if isinstance(value, str):
        return [p.strip() for p in value.split(",") if p.strip()]
    return value or None


def demo_library(config, wanted):
    """The demo library of config ``demo.folder`` (its files are written by rule demo), its poses ``wanted`` (all:
    None); InputError for a pose it does not have."""
    folder = config["demo"]["folder"]
    reference = mesh_file(f"{folder}/{demo.REFERENCE_NAME}{demo.REFERENCE_SUFFIX}")
    poses = [mesh_file(f"{folder}/{p.name}{p.suffix}") for p in demo.POSES]
    if wanted:
        unknown = sorted(set(wanted) - {p.name for p in poses})
        if unknown:
            raise InputError(folder, f"pose(s) not in the demo library: {', '.join(unknown)}")
        poses = [p for p in poses if p.name in wanted]
    return Library(folder=folder, name=config["name"] or "demo", reference=reference, poses=tuple(poses))


def library(config, wanted):
    """The pose library of config ``library`` (a folder, a USD/glTF/Alembic file, or the demo's when None), its
    poses ``wanted`` (all: None); InputError for a problem with its files (one line)."""
    if config["library"] is None:
        return demo_library(config, wanted)
    reference = None if config["reference"] is None else str(config["reference"])  # a frame: 12
    if container_format(config["library"]):  # one container file: its poses unpacked under results/
        name = config["name"] or container_stem(config["library"])
        return container_library(config["library"], f"{config['results']}/{name}/poses", reference=reference,
                                 poses=wanted, name=name, mesh=config["mesh"])
    return discover_library(config["library"], reference=reference, poses=wanted, name=config["name"])


def job_files(folder, job, wildcard="pose"):
    """The log and benchmark files of a rule's job, ``<folder>/logs/{<wildcard>}/<job>.log`` and
    ``<folder>/benchmarks/{<wildcard>}/<job>.tsv``, as the rule declares them (wildcards in braces), (log, benchmark);
    a library's job (no ``wildcard``: None) straight under ``logs/`` and ``benchmarks/``, a job that authors a library
    (``folder`` the library's; ``wildcard`` "") beside its output.

    Examples
    --------
    >>> job_files("results/lib", "verify")
    ('results/lib/logs/{pose}/verify.log', 'results/lib/benchmarks/{pose}/verify.tsv')
    >>> job_files("results/lib", "pack-{repair}", None)
    ('results/lib/logs/pack-{repair}.log', 'results/lib/benchmarks/pack-{repair}.tsv')
    >>> job_files("authored/rig", "skeletal_pose", "")
    ('authored/rig/skeletal_pose.log', 'authored/rig/skeletal_pose.tsv')
    """
    if wildcard == "":
        return f"{folder}/{job}.log", f"{folder}/{job}.tsv"
    sub = f"{{{wildcard}}}/" if wildcard else ""
    return f"{folder}/logs/{sub}{job}.log", f"{folder}/benchmarks/{sub}{job}.tsv"


@contextmanager
def exit_on_input_error():
    """Within: an InputError ends the run with its one line, ``posefix: error: <file>: <problem>`` (exit status 1)."""
    try:
        yield
    except InputError as exc:
        sys.exit(f"posefix: error: {exc}")


def memory_limit_mb(given, local, available_mb):
    """Memory a run may use (MB): ``given`` (the user's ``--resources mem_mb``, or None); else in a ``local`` run
    ``available_mb``, the memory available now; else 0, no limit (on a cluster each job gets its own).

    Examples
    --------
    >>> memory_limit_mb(None, True, 8000), memory_limit_mb(4000, True, 8000), memory_limit_mb(None, False, 8000)
    (8000, 4000, 0)
    """
    if given is not None:
        return int(given)
    return int(available_mb) if local else 0


def read_reference_vertices(results, lib):
    """``{"n": vertex count}`` of the library ``lib``'s reference, or ``{"error": ...}`` while it cannot be read.

    The count comes from ``results/reference.h5`` when validate_reference wrote it from this file, else from the
    mesh file, or from the USD/glTF/Alembic file before it is unpacked. The error is the InputError of a reference
    mesh file that is there and cannot be read (refused before any job), else None (the demo's files not yet
    written, or a bad file that validate_reference names)."""
    checked, reference = Path(results) / "reference.h5", Path(lib.reference.path)
    try:
        if checked.is_file() and checked.stat().st_mtime >= reference.stat().st_mtime:
            return {"n": int(read_artifact(checked, "validate", [])[1]["metrics"]["vertices"])}
        if lib.container and not reference.is_file():  # not yet unpacked
            return {"n": open_container(lib.container, lib.mesh).n}
        return {"n": len(read_reference(lib.reference.path)[0])}
    except InputError as exc:
        return {"error": exc if Path(exc.path) == reference and reference.is_file() else None}
    except Exception:  # noqa: BLE001  (any other unreadable file: validate_reference names it)
        return {"error": None}


def exclude_options(value):
    """classify's command-line options for config ``classify.exclude`` of one pose: a file of vertex ids, a list of
    them, or None.

    Examples
    --------
    >>> exclude_options([3, 1]), exclude_options("ids.txt"), exclude_options(None)
    ('--exclude 3,1', '--exclude-file ids.txt', '')
    """
    if value is None:
        return ""
    if isinstance(value, str):
        return f"--exclude-file {shlex.quote(value)}"
    return "--exclude " + ",".join(str(int(i)) for i in value)


def summary_poses(selected, whole, finished):
    """The poses of the library's summary, in the library's order (``whole``: every pose name of it): this run's
    (``selected``, or None for all) and ``finished``, those an earlier run finished that are still up to date (a
    repair of some poses adds them to the summary rather than replacing it).

    Examples
    --------
    >>> summary_poses(["b"], ["a", "b", "c"], {"c"}), summary_poses(None, ["a", "b"], set())
    (['b', 'c'], ['a', 'b'])
    """
    if not selected:
        return list(whole)
    return [p for p in whole if p in selected or p in finished]


def repair_folders(results, repairs):
    """The folders of the repaired meshes, space-time's first: results/<library>/repaired[-<repair>] (``repairs``:
    the repairs compared beside space-time)."""
    return [f"{results}/repaired", *[f"{results}/repaired-{name}" for name in repairs]]


def repaired_container_files(results, container, repairs):
    """For a library read from a container file: the file of each repair (rule pack), in :func:`repair_folders`;
    else none."""
    if not container:
        return []
    return [f"{folder}/{os.path.basename(container)}" for folder in repair_folders(results, repairs)]


def figure_report(reports, figure, label):
    """The arguments of Snakemake's ``report()`` for one figure of stage render (wildcard ``{pose}``): its file
    under ``reports`` (reports/<library>), its caption ``captions/<figure>.rst`` and its ``label``."""
    return {"value": f"{reports}/figures/{{pose}}/{figure}.png", "caption": f"captions/{figure}.rst",
            "category": "2. Poses", "subcategory": "{pose}", "labels": {"pose": "{pose}", "figure": label}}


def report_targets(reports, poses, figures):
    """The report's files under ``reports``: each pose's ``figures`` (names) and its downstream figure, the summary,
    the overview and the 3D viewer.

    Examples
    --------
    >>> report_targets("r", ["a"], ["fit"])
    ['r/figures/a/fit.png', 'r/figures/a/downstream.png', 'r/summary.json', 'r/overview.png', 'r/viewer.html']
    """
    return [*[f"{reports}/figures/{p}/{f}.png" for p in poses for f in figures],
            *[f"{reports}/figures/{p}/downstream.png" for p in poses],
            f"{reports}/summary.json", f"{reports}/overview.png", f"{reports}/viewer.html"]
