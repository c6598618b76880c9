"""The ``posefix`` command: run the packaged workflow on a pose library from any folder.

``posefix repair LIBRARY`` runs ``snakemake`` with the packaged workflow's Snakefile in the current folder
(``results/``, ``reports/`` go there), ``posefix report LIBRARY`` writes the self-contained HTML report
of a finished run. Snakemake's own output goes to ``posefix-logs/<time>.log``; the terminal shows the
progress and the posefix lines, and a failed run ends with the posefix error lines of the stages (not
Snakemake's traceback) and the log's path. The progress and the failed jobs come from Snakemake's events, which its
logger plugin ``posefix`` writes to a pipe (:mod:`posefix.workflow.events`), not from its text. Recovery after a hard kill needs nothing: the workflow
removes stale locks and its default profile reruns incomplete jobs.
"""

import argparse
import json
import os
import queue
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from posefix.io.containers import CONTAINER_SUFFIXES, container_format, container_stem
from posefix.report.tables import entry_status
from posefix import __version__
from posefix.workflow.config_check import nested
from posefix.workflow.events import failed_job_errors, failure_line
from posefix.workflow.files import workflow_folder
from posefix.workflow.progress import RunProgress

WORKFLOW = workflow_folder()
"""The workflow's folder: Snakefile, rules, stages, profiles (in the wheel, or the checkout of ``pip install -e``)."""

SHOWN = ("posefix", "Nothing to be done", "This was a dry-run")
"""The starts of Snakemake's output lines shown as they are, besides the stages' warnings (:func:`shown`; the
progress: :class:`~posefix.workflow.progress.RunProgress`)."""


class _OneLineParser(argparse.ArgumentParser):
    """argparse's parser, whose errors are one line (argparse's own: its usage, several lines, then the error)."""

    def error(self, message):
        self.exit(2, f"posefix: error: {message} (see {self.prog} --help)\n")


def build_parser():
    parser = _OneLineParser(prog="posefix", description=__doc__.split("\n\n")[0].replace("``", ""))
    parser.add_argument("--version", action="version", version=f"posefix {__version__}")
    commands = parser.add_subparsers(dest="command", required=True)
    repair = commands.add_parser("repair", help="repair a pose library (the whole workflow)")
    report = commands.add_parser("report", help="the HTML report of a repaired library")
    for sub in (repair, report):
        sub.add_argument("library", nargs="?", default=None,
                         help="folder of the pose library (a reference and its poses), or one USD, glTF or Alembic "
                              "file of its poses; none: the built-in demo")
        sub.add_argument("--config", nargs="+", default=[], metavar="KEY=VALUE",
                         help="config overrides, as snakemake --config (e.g. reference=a.obj poses=b,c), nested "
                              "keys with dots (fit.batch=64)")
    repair.add_argument("--cores", type=int, default=2, help="cores to use (default 2)")
    repair.add_argument("--profile", default=None,
                        help="workflow profile: a name under the workflow's profiles/ (slurm) or a folder")
    repair.add_argument("--memory", type=float, default=None, metavar="GB",
                        help="memory the run may use (default: what is available when it starts); jobs that would "
                        "not fit together wait, a library too large for it is refused before anything runs")
    repair.add_argument("--dry-run", "-n", action="store_true", help="only show what would run")
    return parser


def snakemake_command(args):
    """The snakemake command line (list of str) for parsed ``args``."""
    library = [f"library={Path(args.library).resolve()}"] if args.library else []
    command = [sys.executable, "-m", "snakemake", "-s", str(WORKFLOW / "Snakefile"), "--config", *library,
               *nested_config(args.config)]
    if args.command == "report":
        return command + report_poses(args) + ["--report", f"reports/{library_name(args)}/report.html"]
    command += ["--cores", str(args.cores)]
    if args.memory is not None:
        command += ["--resources", f"mem_mb={int(args.memory * 1000)}"]
    if args.profile:
        command += ["--workflow-profile", str(profile_folder(args.profile))]
    return command + (["--dry-run", "--quiet", "rules"] if args.dry_run else [])


def nested_config(entries):
    """``--config`` entries (list of str) with dotted keys (``fit.batch=64``, which Snakemake refuses: "Config entry
    must start with a valid identifier") as one nested entry per section (``fit={"batch": "64"}``; Snakemake keeps
    only the last entry of a key, and the workflow types the text by the schema); the others as they are.

    Examples
    --------
    >>> nested_config(["poses=a,b", "fit.batch=64", "fit.eps_rel=1e-3", "verify.finish=snap"])
    ['poses=a,b', 'fit={"batch": "64", "eps_rel": "1e-3"}', 'verify={"finish": "snap"}']
    """
    plain = [entry for entry in entries if "." not in entry.partition("=")[0]]
    sections = nested(dict(entry.partition("=")[::2] for entry in entries if entry not in plain))
    return plain + [f"{name}={json.dumps(value)}" for name, value in sections.items()]


def report_poses(args):
    """``["poses=a,b"]``: the poses of the library's summary.json in the current folder, that the report covers
    (Snakemake's report needs every job of the run done; a repair of some poses did not run the others), when
    ``--config`` names no poses itself; else ``[]``."""
    summary = Path("reports") / library_name(args) / "summary.json"
    if any(entry.startswith("poses=") for entry in args.config) or not summary.is_file():
        return []
    try:
        poses = [entry["pose"] for entry in json.loads(summary.read_text())["poses"]]
    except (ValueError, KeyError, TypeError):
        return []
    return [f"poses={','.join(poses)}"] if poses else []


def library_name(args):
    """The library's name in results/ and reports/: ``name=`` of ``--config`` if given, else the folder's name or
    the USD or glTF file's without its extension (``demo`` without one)."""
    names = [entry.split("=", 1)[1] for entry in args.config if entry.startswith("name=")]
    if names and names[-1]:
        return names[-1]
    if args.library and container_format(args.library):
        return container_stem(args.library)
    return Path(args.library).resolve().name if args.library else "demo"


def profile_folder(profile):
    """The folder of a ``--profile``: a name under the workflow's ``profiles/`` or a folder path, (Path)."""
    shipped = WORKFLOW / "profiles" / profile
    return shipped if shipped.is_dir() else Path(profile).resolve()


def _is_key(text):
    """Whether ``text`` is a config key, a name with dots between (``fit.batch``)."""
    return not text.startswith(".") and text.replace(".", "_").isidentifier()


def argument_problem(args):
    """What is wrong with parsed ``args`` before anything runs, one line (str), or None."""
    if not (WORKFLOW / "Snakefile").is_file():
        return f"no workflow beside the package ({WORKFLOW}): reinstall posefix (pip install posefix, or pip install -e .)"
    if args.library is not None and not Path(args.library).is_dir():
        if not container_format(args.library):
            return f"{args.library}: not a folder, nor a USD, glTF or Alembic file ({', '.join(CONTAINER_SUFFIXES)})"
        if not Path(args.library).is_file():
            return f"{args.library}: no such file"
    loose = [entry for entry in args.config if "=" not in entry or not _is_key(entry.partition("=")[0])]
    if loose and "=" in loose[0]:
        return f"--config {loose[0]}: the key before = is not a config key (KEY=VALUE, e.g. fit.batch=64)"
    if loose:  # --config takes every word after it: a library named after it is one
        return (f"--config {loose[0]}: not KEY=VALUE (name the library before --config: posefix {args.command} "
                f"<library> --config KEY=VALUE ...)")
    if args.command == "repair" and args.cores < 1:
        return f"--cores {args.cores}: needs at least 1 core"
    if args.command == "repair" and args.memory is not None and args.memory <= 0:
        return f"--memory {args.memory:g}: needs more than 0 GB"
    if args.command == "repair" and args.profile and not profile_folder(args.profile).is_dir():
        shipped = ", ".join(sorted(p.name for p in (WORKFLOW / "profiles").iterdir() if p.is_dir()))
        return f"--profile {args.profile}: no such profile (shipped: {shipped}; or give a folder)"
    if args.command == "repair" and args.profile and not any(
            (profile_folder(args.profile) / name).is_file() for name in ("config.yaml", "profile.yaml")):
        return f"--profile {args.profile}: the folder has no config.yaml (a Snakemake profile's settings)"
    return None


def run(command, log_path, dry_run=False):
    """Run ``command`` (Snakemake's, without its logger options: :func:`with_events` adds them), its output into
    ``log_path`` (line by line); onto stdout the progress (:class:`~posefix.workflow.progress.RunProgress`, from
    Snakemake's events; a dry run: Snakemake's table of the jobs) and the lines :func:`shown`, the posefix error lines
    once each onto stderr: the exit code, the error lines and the events (list of dict)."""
    errors, events, later, progress = [], [], [], RunProgress()
    log_path.parent.mkdir(parents=True, exist_ok=True)
    read_end, write_end = os.pipe()
    with open(log_path, "w", encoding="utf-8", buffering=1) as log, subprocess.Popen(
            with_events(command, write_end), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
            errors="replace", start_new_session=True, pass_fds=(write_end,)) as child:
        os.close(write_end)
        items = queue.Queue()
        for kind, stream in (("line", child.stdout), ("event", open(read_end, encoding="utf-8", errors="replace"))):
            threading.Thread(target=_pump, args=(kind, stream, items), daemon=True).start()
        try:
            for kind, item in _items(items, progress):
                if kind == "event":
                    events.append(item)
                    _show(_event_lines(item, progress, dry_run))
                    continue
                log.write(item)
                error = item.startswith("posefix") and "error:" in item
                if error and item not in errors:  # once, to stderr
                    errors.append(item)
                    print(item, end="", file=sys.stderr, flush=True)
                elif not error and shown(item):
                    (later.append if dry_run else print)(item.rstrip("\n"))
            _show(later)  # a dry run's lines after its table of the jobs (an event: the two streams interleave)
            return child.wait(), errors, events
        except KeyboardInterrupt:  # Ctrl-C: stop Snakemake and its jobs, quietly
            child.send_signal(signal.SIGINT)
            child.wait()
            return 130, errors, events


def with_events(command, fd):
    """Snakemake's ``command`` (list of str) with the logger plugin ``posefix`` writing its events to the file
    descriptor ``fd`` (int)."""
    return [*command, "--logger", "posefix", "--logger-posefix-events", f"/dev/fd/{fd}"]


def shown(line):
    """Whether Snakemake's output ``line`` (str) is shown as it is: it starts with one of :data:`SHOWN`, or it is a
    stage's warning (``12:00:01 posefix fit: warning: ...``)."""
    words = line.split(" ", 3)
    return line.startswith(SHOWN) or (len(words) == 4 and words[1] == "posefix" and words[3].startswith("warning:"))


def _event_lines(event, progress, dry_run):
    """The lines to show for Snakemake's ``event`` (dict): a dry run's table of the jobs, else the progress."""
    if dry_run:
        return [event["msg"].rstrip("\n")] if event["event"] == "run_info" and "msg" in event else []
    return progress.feed(event)


def _pump(kind, stream, items):
    """Put ``(kind, line)`` for the lines of ``stream`` (the events parsed) into the queue ``items``, then None."""
    with stream:
        for line in stream:
            try:
                items.put((kind, json.loads(line) if kind == "event" else line))
            except ValueError:  # (never expected: the plugin writes whole lines)
                continue
    items.put(None)


def _items(items, progress):
    """The ``(kind, item)`` pairs of the queue ``items`` until both streams ended; while none comes, what
    ``progress`` says of the jobs running."""
    streams = 2
    while streams:
        try:
            item = items.get(timeout=5.0)
        except queue.Empty:
            _show(progress.idle())
            continue
        streams -= item is None
        if item is not None:
            yield item


def _show(lines):
    for line in lines:
        print(line, flush=True)


def finished_lines(reports, results, most=10, container=None):
    """What a finished repair made and where (list of str): each pose's status and intersecting faces (``most``
    poses at most, the first that are not ok first), the repaired meshes (and file: ``container``, the file name of
    a USD or glTF library), the summary page and the 3D viewer."""
    try:
        entries = json.loads((reports / "summary.json").read_text())["poses"]
    except (OSError, ValueError, KeyError):
        return []
    statuses = [entry_status(entry) for entry in entries]
    kinds = [kind for kind, _ in statuses]
    counts = ", ".join(f"{kinds.count(kind)} {kind}" for kind in ("ok", "fallback", "check"))
    lines = [f"posefix: {len(entries)} poses repaired: {counts}"]
    for i in sorted(range(len(entries)), key=lambda i: kinds[i] == "ok")[:most]:
        faces, (kind, reason) = entries[i]["intersecting_faces"], statuses[i]
        lines.append(f"  {entries[i]['pose']}: {kind}{f' ({reason})' if reason else ''}; intersecting faces: "
                     f"{faces['target']} in the target, {faces['repaired']} repaired ({faces['repaired_new']} new)")
    if len(entries) > most:
        lines.append(f"  ... and {len(entries) - most} more (the summary page)")
    pages = [("repaired meshes", results / "repaired"), ("summary page", reports / "summary.html"),
             ("3D viewer", reports / "viewer.html")]
    if container:
        pages.insert(1, ("repaired file", results / "repaired" / container))
    return lines + [f"posefix: {what}: {path}" for what, path in pages if path.exists()]


def print_missed_errors(shown, events, text):
    """Print to stderr the failed jobs' error lines (:func:`~posefix.workflow.events.failed_job_errors`, from their
    log files, which Snakemake's ``events`` name) that the run's output did not show (``shown``: the lines it did):
    two jobs writing at once can break a line of Snakemake's merged output (a test saw it on a loaded machine), their
    log files cannot. Where no job left one, the run's :func:`~posefix.workflow.events.failure_line` (from the events,
    else Snakemake's ``text``, list of str), unless the output showed an error line."""
    shown = {line.rstrip("\n") for line in shown}
    lines = failed_job_errors(events, Path.cwd())
    if lines == [failure_line(events, Path.cwd())]:
        lines = [failure_line(events, Path.cwd(), text)]
    for line in lines:
        if line not in shown and (not shown or not line.startswith("posefix: ")):
            print(line, file=sys.stderr)


def main(argv=None):
    args = build_parser().parse_args(argv)
    problem = argument_problem(args)
    if problem:
        sys.exit(f"posefix: error: {problem}")
    log_path = Path("posefix-logs") / time.strftime(f"{args.command}-%Y%m%d-%H%M%S.log")
    try:
        log_path.parent.mkdir(exist_ok=True)
    except OSError as exc:
        sys.exit(f"posefix: error: {Path.cwd()}: the run's log folder {log_path.parent} cannot be made here "
                 f"({exc.strerror}); run posefix in a folder you can write")
    code, errors, events = run(snakemake_command(args), log_path, dry_run=args.command == "repair" and args.dry_run)
    if code == 0 and args.command == "repair" and not args.dry_run:
        container = Path(args.library).name if args.library and container_format(args.library) else None
        print("\n".join(finished_lines(Path("reports") / library_name(args), Path("results") / library_name(args),
                                       container=container)))
    if code == 130:
        print("posefix: interrupted; run the same command again to go on", file=sys.stderr)
    elif code != 0:
        print_missed_errors(errors, events, log_path.read_text(errors="replace").splitlines())
        print(f"posefix: Snakemake's full output: {log_path}", file=sys.stderr)
    sys.exit(code)


if __name__ == "__main__":
    main()
