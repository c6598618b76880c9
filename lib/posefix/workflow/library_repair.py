"""A pose library repaired from Python (``posefix.repair_library``): the workflow run through Snakemake's Python
API in this process, as ``posefix repair`` runs it (the same rules, config and workflow profile settings), with no
subprocess of the ``posefix`` command.

Snakemake's output and the stages' go to ``<out>/posefix-logs/api-<time>.log``; the progress goes to the
``posefix.workflow.library_repair`` logger. A failed run raises :class:`~posefix.io.errors.PosefixError` with the
first failed job's one-line error (as the command prints it).

Examples: ``docs/api.md``.
"""

import contextlib
import glob
import json
import logging
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace

from posefix.io.containers import container_format
from posefix.io.errors import PosefixError
from posefix.report.contents import REPAIRS as LABELS, SPACETIME
from posefix.report.tables import entry_status
from posefix.workflow.command import library_name
from posefix.workflow.config_check import nested
from posefix.workflow.events import EventRecorder, failed_job_errors
from posefix.workflow.files import workflow_folder

log = logging.getLogger(__name__)

REPAIRS = tuple(LABELS.values())
"""The repairs: space-time always runs; the others are compared beside it (config ``repairs``)."""


@dataclass
class PoseOutcome:
    """One pose of a repaired library.

    Attributes
    ----------
    name : str
    status, reason : str
        ``ok``, ``fallback`` or ``check``, and why (``summary.json``'s).
    intersecting_faces : dict
        ``reference``, ``target``, ``repaired``, ``repaired_new`` (the space-time repair's).
    repaired : dict of str -> Path
        Repaired mesh file per repair (``space-time``, ``contact``, ...); none for a USD or glTF library, whose
        repaired poses are packed into :attr:`LibraryRepair.containers`.
    entry : dict
        The pose's whole ``summary.json`` entry.
    """

    name: str
    status: str
    reason: str
    intersecting_faces: dict
    repaired: dict
    entry: dict


@dataclass
class LibraryRepair:
    """A library repaired by :func:`repair_library`: its poses, and where the results, reports and log are."""

    name: str
    poses: list
    results: Path
    reports: Path
    log: Path
    containers: list = field(default_factory=list)


def repair_library(library=None, out=".", repairs=("space-time",), cores=2, config=None):
    """Repair a pose library with the workflow, as ``posefix repair`` does.

    Parameters
    ----------
    library : str or Path, optional
        Folder of the library (a reference and its poses), or one USD or glTF file of its poses; None: the built-in
        demo.
    out : str or Path
        Folder the run works in: ``results/``, ``reports/`` and ``posefix-logs/`` go there.
    repairs : sequence of str
        Of :data:`REPAIRS`; space-time always runs, the others beside it.
    cores : int
    config : dict, optional
        Config keys, dotted for nested ones (``{"poses": "a,b", "fit.batch": 64}``) or sections
        (``{"fit": {"batch": 64}}``), as ``--config`` (``docs/configuration.md``).

    Returns
    -------
    LibraryRepair

    Raises
    ------
    PosefixError
        The run failed: the first failed job's one-line error, or why the run could not start.
    """
    unknown = sorted(set(repairs) - set(REPAIRS))
    if unknown:
        raise PosefixError(f"repairs: {unknown[0]!r} is not a repair (one of {', '.join(REPAIRS)})")
    if cores < 1:
        raise PosefixError(f"cores={cores}: needs at least 1 core")
    settings = nested(config or {}) | {"repairs": [r for r in REPAIRS[1:] if r in repairs]}
    if library is not None:
        settings["library"] = str(Path(library).resolve())
    out = Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    log_path = _new_log(out / "posefix-logs")
    _run(settings, out, cores, log_path)
    name = library_name(SimpleNamespace(library=library, config=[f"name={settings.get('name') or ''}"]))
    return _outcome(name, out / settings.get("results", "results") / name,
                    out / settings.get("reports", "reports") / name, log_path)


def _new_log(folder):
    """A new file's path in ``folder`` (made if need be): ``api-<date>-<time>.log``, ``-2``, ``-3`` ... after it
    when a run of the same second has one."""
    folder.mkdir(exist_ok=True)
    stem, k = time.strftime("api-%Y%m%d-%H%M%S"), 1
    while (folder / f"{stem}{f'-{k}' if k > 1 else ''}.log").exists():
        k += 1
    return folder / f"{stem}{f'-{k}' if k > 1 else ''}.log"


def _run(settings, out, cores, log_path):
    """Run the workflow in ``out`` with the config ``settings`` on ``cores``; its output into ``log_path``, the
    progress onto this module's logger; :class:`PosefixError` when it fails."""
    cwd, environment = Path.cwd(), dict(os.environ)  # the Snakefile sets PATH and POSEFIX_BLENDER: not the caller's
    progress = _Progress()
    try:
        with open(log_path, "w", encoding="utf-8", buffering=1) as stream, _output_into(stream):
            _execute(settings, out, cores, progress)
    except (Exception, SystemExit) as exc:  # noqa: BLE001 (Snakemake's and the Snakefile's sys.exit alike)
        raise PosefixError(_failure(exc, progress.events, out)) from None
    finally:
        os.chdir(cwd)
        os.environ.clear()
        os.environ.update(environment)


@contextlib.contextmanager
def _output_into(stream):
    """Within: this process's standard output and error go to ``stream`` (a text file), Python's and the file
    descriptors that the jobs inherit, and so does Snakemake's logger; the logging handlers that wrote to the
    standard streams (the caller's, on this module's logger and its parents) write to the terminal still, so the
    progress lines reach it."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    terminal = os.fdopen(os.dup(2), "w", buffering=1)
    handlers = [h for h in _handlers(log) if type(h) is logging.StreamHandler and h.stream in (sys.stdout, sys.stderr)]
    streams = [h.setStream(terminal) for h in handlers]
    snakemake = logging.getLogger("snakemake")
    propagate, snakemake.propagate = snakemake.propagate, False
    try:
        for fd in (1, 2):
            os.dup2(stream.fileno(), fd)
        with contextlib.redirect_stdout(stream), contextlib.redirect_stderr(stream):
            yield
    finally:
        for fd, copy in zip((1, 2), saved):
            os.dup2(copy, fd)
            os.close(copy)
        for handler, previous in zip(handlers, streams):
            handler.setStream(previous)
        snakemake.propagate = propagate
        terminal.close()


def _handlers(logger):
    """The handlers that see ``logger``'s records: its own and its parents' while they propagate, list."""
    out = []
    while logger is not None:
        out += logger.handlers
        logger = logger.parent if logger.propagate else None
    return out


def _execute(settings, out, cores, handler):
    """The workflow's run through Snakemake's API, with the workflow profile's settings (rerun-incomplete,
    keep-going: ``profiles/default``), its events into ``handler`` (:class:`_Progress`)."""
    from snakemake.api import SnakemakeApi
    from snakemake.settings.types import (ConfigSettings, DAGSettings, ExecutionSettings, OutputSettings,
                                          ResourceSettings)

    with SnakemakeApi(OutputSettings()) as api:
        logging.getLogger("snakemake").addHandler(handler)
        try:
            workflow = api.workflow(resource_settings=ResourceSettings(cores=cores),
                                    config_settings=ConfigSettings(config=settings),
                                    snakefile=workflow_folder() / "Snakefile", workdir=out)
            dag = workflow.dag(DAGSettings(force_incomplete=True))
            dag.execute_workflow(execution_settings=ExecutionSettings(keep_going=True))
        finally:
            logging.getLogger("snakemake").removeHandler(handler)


class _Progress(EventRecorder):
    """Snakemake's events, kept (:class:`~posefix.workflow.events.EventRecorder`), its progress as
    ``posefix.workflow.library_repair`` lines: ``3 of 17 steps done``."""

    def emit(self, record):
        super().emit(record)
        if str(getattr(record, "event", "")) == "progress":
            log.info("%d of %d steps done", record.done, record.total)


def _failure(exc, events, out):
    """The one line of a failed run: the first failed job's posefix error (Snakemake's ``events``, list of dict, name
    their logs), the Snakefile's refusal, or the exception's first line (str)."""
    if isinstance(exc, SystemExit) and isinstance(exc.code, str):
        return exc.code.splitlines()[0].removeprefix("posefix: error: ")
    lines = failed_job_errors(events, out)
    first = lines[0].split("error: ", 1)[-1] if lines else ""
    return first or (str(exc).strip().splitlines() or [type(exc).__name__])[0]


def _outcome(name, results, reports, log_path):
    """The :class:`LibraryRepair` of a finished run, from its ``summary.json``."""
    entries = json.loads((reports / "summary.json").read_text())["poses"]
    poses = []
    for entry in entries:
        kind, reason = entry_status(entry)
        folders = {SPACETIME: "repaired"} | {repair: f"repaired-{repair}" for repair in entry.get("repairs", {})}
        meshes = {repair: sorted(results.glob(f"{folder}/{glob.escape(entry['pose'])}.*"))
                  for repair, folder in folders.items()}
        poses.append(PoseOutcome(entry["pose"], kind, reason, entry["intersecting_faces"],
                                 {repair: files[0] for repair, files in meshes.items() if files}, entry))
    containers = sorted(p for p in results.glob("repaired*/*") if container_format(p))
    return LibraryRepair(name, poses, results, reports, log_path, containers)
