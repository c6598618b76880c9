"""The ``posefix`` command: run the packaged workflow on a pose library from any folder.

``posefix repair LIBRARY`` runs ``snakemake`` with the packaged workflow's Snakefile in the current folder
(``results/``, ``reports/`` go there), ``posefix report LIBRARY`` writes the self-contained HTML report
of a finished run. Snakemake's own output goes to ``posefix-logs/<time>.log``; the terminal shows the
progress and the posefix lines, and a failed run ends with the posefix error lines of the stages (not
Snakemake's traceback) and the log's path. Recovery after a hard kill needs nothing: the workflow
removes stale locks and its default profile reruns incomplete jobs.
"""

import argparse
import json
import queue
import re
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
from posefix.workflow.files import workflow_folder
from posefix.workflow.progress import RunProgress

WORKFLOW = workflow_folder()
"""The workflow's folder: Snakefile, rules, stages, profiles (in the wheel, or the checkout of ``pip install -e``)."""

SHOWN = re.compile(r"^(posefix\b|Nothing to be done|This was a dry-run|[\d:]+ posefix [\w-]+: warning:)")
"""Snakemake's output lines shown as they are (the progress: :class:`~posefix.workflow.progress.RunProgress`)."""

FAILURES = (
    (re.compile(r"LockException|Directory cannot be locked"),
     "{folder}: another Snakemake run is working in this folder; wait for it to finish (if none is running: "
     "snakemake --unlock)"),
    (re.compile(r"(?P<cause>.*No space left on device.*)"),
     "no space left on device ({cause}); free some disk, then run the same command again"),
    (re.compile(r"(?P<cause>.*Permission denied.*)"), "permission denied ({cause})"),
    (re.compile(r"(?P<cause>profile directory given \(.*\), but no profile.yaml \(or config.yaml\) found)"),
     "Snakemake: {cause} (a --profile or SNAKEMAKE_PROFILE that names no profile)"),
    (re.compile(r"^\s*(?P<cause>(WildcardError|MissingInputException|Missing input files|WorkflowError|"
                r"SyntaxError|ValueError|KeyError)\b.*)"), "{cause}"),  # (not a traceback's "raise ValueError(")
)
"""Snakemake failures that precede or stop the jobs (no stage wrote a posefix line), as one line each: a pattern
of the log and its message (``folder``: the run's folder; ``cause``: the matched log line)."""


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


def argument_problem(args):
    """What is wrong with parsed ``args`` before anything runs, one line (str), or None."""
    if not (WORKFLOW / "Snakefile").is_file():
        return f"no workflow beside the package ({WORKFLOW}): reinstall posefix (pip install posefix, or pip install -e .)"
    if args.library is not None and not Path(args.library).is_dir():
        if not container_format(args.library):
            return f"{args.library}: not a folder, nor a USD, glTF or Alembic file ({', '.join(CONTAINER_SUFFIXES)})"
        if not Path(args.library).is_file():
            return f"{args.library}: no such file"
    loose = [entry for entry in args.config if not re.match(r"[A-Za-z_][\w.]*=", entry)]
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
    """Run ``command``, its output into ``log_path`` (line by line); onto stdout the progress
    (:class:`~posefix.workflow.progress.RunProgress`; a dry run: Snakemake's table of the jobs) and the lines
    :data:`SHOWN`, the posefix error lines once each onto stderr: the exit code and the error lines."""
    errors, progress = [], RunProgress()
    log_path.parent.mkdir(parents=True, exist_ok=True)
    with open(log_path, "w", encoding="utf-8", buffering=1) as log, subprocess.Popen(
            command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, errors="replace",
            start_new_session=True) as child:
        lines = queue.Queue()
        threading.Thread(target=_pump, args=(child.stdout, lines), daemon=True).start()
        try:
            table = False  # Snakemake's table of the jobs to run, from "Job stats:" to its "total" line
            for line in iter(lambda: _next_line(lines, progress), None):
                log.write(line)
                table = dry_run and (table or line.startswith("Job stats:"))
                error = line.startswith("posefix") and "error:" in line
                if error and line not in errors:  # once, to stderr
                    errors.append(line)
                    print(line, end="", file=sys.stderr, flush=True)
                elif not error and (table or SHOWN.match(line)):
                    print(line, end="", flush=True)
                elif not dry_run:
                    _show(progress.feed(line))
                table = table and not line.startswith("total")
            return child.wait(), errors
        except KeyboardInterrupt:  # Ctrl-C: stop Snakemake and its jobs, quietly
            child.send_signal(signal.SIGINT)
            child.wait()
            return 130, errors


def _pump(stream, lines):
    """Put the lines of ``stream`` into the queue ``lines``, then None."""
    for line in stream:
        lines.put(line)
    lines.put(None)


def _next_line(lines, progress):
    """The next line of Snakemake's output from the queue ``lines`` (None at its end); while none comes, what
    ``progress`` says of the jobs running."""
    while True:
        try:
            return lines.get(timeout=5.0)
        except queue.Empty:
            _show(progress.idle())


def _show(lines):
    for line in lines:
        print(line, flush=True)


def failure_line(log_text, folder):
    """The one-line cause of a run that failed with no posefix error line, from Snakemake's log (str)."""
    lines = log_text.splitlines()
    for pattern, message in FAILURES:
        for k, line in enumerate(lines):
            match = pattern.search(line)
            if match:
                cause = match.groupdict().get("cause", "").strip()
                if cause.endswith(":"):  # "WorkflowError:", the explanation on the next line that says something
                    cause = " ".join([cause, *[text.strip() for text in lines[k + 1:] if text.strip()][:1]])
                return "posefix: error: " + message.format(folder=folder, cause=cause[:300])
    raised = _last_exception(lines)
    if raised:
        return f"posefix: error: {raised[:300]} (Snakemake stopped before any stage; see its full output below)"
    return "posefix: error: the run failed before any stage reported (see Snakemake's full output below)"


def _last_exception(lines):
    """The last exception a traceback in ``lines`` (list of str) names, as ``Name: message`` (Snakemake writes
    ``Name in file F, line N:`` with the message on the next line), or None.

    Examples
    --------
    >>> _last_exception(["Traceback ...", '  File "x.py"', "NotADirectoryError: [Errno 20] Not a directory: 'r/a'"])
    "NotADirectoryError: [Errno 20] Not a directory: 'r/a'"
    >>> _last_exception(['FileExistsError in file "Snakefile", line 37:', "[Errno 17] File exists: '.snakemake'"])
    "FileExistsError: [Errno 17] File exists: '.snakemake'"
    """
    for k in range(len(lines) - 1, -1, -1):
        match = re.match(r"(?P<name>[A-Z]\w*(Error|Exception))(?P<rest>: .*| in file .*:)?$", lines[k].strip())
        if match and (match.group("rest") or "").startswith(" in file"):
            following = [text.strip() for text in lines[k + 1:] if text.strip()][:1]
            return ": ".join([match.group("name"), *following])
        if match:
            return match.group("name") + (match.group("rest") or "")
    return None


def failed_job_errors(log_text, folder):
    """The posefix error lines of the jobs that failed, from Snakemake's log (str) and the jobs' log files that it
    names (relative to ``folder``), once each in order; ``[`` :func:`failure_line` ``]`` when there are none."""
    lines = []
    for path in re.findall(r"log: (.+?) \(check log file\(s\) for error details\)", log_text):
        for candidate in path.split(", "):
            try:
                text = (Path(folder) / candidate).read_text(errors="replace")
            except OSError:
                continue
            lines += [line for line in text.splitlines() if re.match(r"posefix [\w-]+: error:", line)]
    return list(dict.fromkeys(lines)) or [failure_line(log_text, folder)]


def recap_line(line):
    """A failed job's posefix error line as the run's recap shows it at the end (``posefix validate: error: X`` ->
    ``posefix: failed in validate: X``): the error itself stays the one line that says ``error:``."""
    match = re.match(r"posefix ([\w-]+): error: (.*)", line)
    return f"posefix: failed in {match.group(1)}: {match.group(2)}" if match else line


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


def print_missed_errors(shown, log_text):
    """Print to stderr the failed jobs' error lines (:func:`failed_job_errors`, from their log files) that the run's
    output did not show (``shown``: the lines it did): two jobs writing at once can break a line of Snakemake's
    merged output (a test saw it on a loaded machine), their log files cannot. Where no job left one, the run's
    :func:`failure_line`, unless the output showed an error line."""
    shown = {line.rstrip("\n") for line in shown}
    for line in failed_job_errors(log_text, Path.cwd()):
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
    code, errors = run(snakemake_command(args), log_path, dry_run=args.command == "repair" and args.dry_run)
    if code == 0 and args.command == "repair" and not args.dry_run:
        container = Path(args.library).name if args.library and container_format(args.library) else None
        print("\n".join(finished_lines(Path("reports") / library_name(args), Path("results") / library_name(args),
                                       container=container)))
    if code == 130:
        print("posefix: interrupted; run the same command again to go on", file=sys.stderr)
    elif code != 0:
        print_missed_errors(errors, log_path.read_text(errors="replace"))
        print(f"posefix: Snakemake's full output: {log_path}", file=sys.stderr)
    sys.exit(code)


if __name__ == "__main__":
    main()
