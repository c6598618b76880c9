"""The ``posefix`` command: run the packaged workflow on a pose library from any folder.

``posefix repair LIBRARY`` runs ``snakemake`` with this checkout's Snakefile in the current folder
(``results/``, ``reports/`` go there), ``posefix report LIBRARY`` writes the self-contained HTML report
of a finished run. Snakemake's own output goes to ``posefix-logs/<time>.log``; the terminal shows the
progress and the posefix lines, and a failed run ends with the posefix error lines of the stages (not
Snakemake's traceback) and the log's path. Recovery after a hard kill needs nothing: the workflow
removes stale locks and its default profile reruns incomplete jobs.
"""

import argparse
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

WORKFLOW = Path(__file__).resolve().parents[3]
"""The checkout the package is installed from (``pip install -e``): Snakefile, rules, stages, profiles."""

SHOWN = re.compile(r"^(posefix\b|\d+ of \d+ steps|Nothing to be done)")


def build_parser():
    parser = argparse.ArgumentParser(prog="posefix", description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    repair = commands.add_parser("repair", help="repair a pose library (the whole workflow)")
    report = commands.add_parser("report", help="the HTML report of a repaired library")
    for sub in (repair, report):
        sub.add_argument("library", help="folder of the pose library (a reference and its poses)")
        sub.add_argument("--config", nargs="+", default=[], metavar="KEY=VALUE",
                         help="config overrides, as snakemake --config (e.g. reference=a.obj poses=b,c)")
    repair.add_argument("--cores", type=int, default=2, help="cores to use (default 2)")
    repair.add_argument("--profile", default=None,
                        help="workflow profile: a name under the workflow's profiles/ (slurm) or a folder")
    repair.add_argument("--dry-run", "-n", action="store_true", help="only show what would run")
    return parser


def snakemake_command(args):
    """The snakemake command line (list of str) for parsed ``args``."""
    command = [sys.executable, "-m", "snakemake", "-s", str(WORKFLOW / "Snakefile"),
               "--config", f"library={Path(args.library).resolve()}", *args.config]
    if args.command == "report":
        name = Path(args.library).resolve().name
        return command + ["--report", f"reports/{name}/report.html"]
    command += ["--cores", str(args.cores)]
    if args.profile:
        profile = WORKFLOW / "profiles" / args.profile
        command += ["--workflow-profile", str(profile if profile.is_dir() else Path(args.profile).resolve())]
    return command + (["--dry-run"] if args.dry_run else [])


def run(command, log_path):
    """Run ``command``, its output into ``log_path`` and the lines :data:`SHOWN` onto the terminal: the exit
    code and the posefix error lines."""
    errors = []
    log_path.parent.mkdir(parents=True, exist_ok=True)
    with open(log_path, "w", encoding="utf-8") as log, subprocess.Popen(
            command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, errors="replace",
            start_new_session=True) as child:
        try:
            for line in child.stdout:
                log.write(line)
                if SHOWN.match(line):
                    print(line, end="", flush=True)
                if line.startswith("posefix") and "error:" in line and line not in errors:
                    errors.append(line)
            return child.wait(), errors
        except KeyboardInterrupt:  # Ctrl-C: stop Snakemake and its jobs, quietly
            child.send_signal(signal.SIGINT)
            child.wait()
            return 130, errors


def main(argv=None):
    args = build_parser().parse_args(argv)
    if not (WORKFLOW / "Snakefile").is_file():
        sys.exit(f"posefix: error: no workflow next to the package ({WORKFLOW}): install it with pip install -e")
    if not Path(args.library).is_dir():
        sys.exit(f"posefix: error: {args.library}: not a folder")
    log_path = Path("posefix-logs") / time.strftime(f"{args.command}-%Y%m%d-%H%M%S.log")
    code, errors = run(snakemake_command(args), log_path)
    if code == 130:
        print("posefix: interrupted; run the same command again to go on", file=sys.stderr)
    elif code != 0:
        print("".join(errors) if errors else "posefix: the run failed (no posefix error line, see the log)",
              end="" if errors else "\n", file=sys.stderr)
        print(f"posefix: Snakemake's full output: {log_path}", file=sys.stderr)
    sys.exit(code)


if __name__ == "__main__":
    main()
