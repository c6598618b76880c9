"""Stage overview: one page comparing all poses of a library, for the report.

Reads ``summary.json`` and writes ``overview.png`` (intersections before/after, deviation against
the bar, centres and fallback vertices, seconds per stage, one column per pose) and
``summary.html`` (the summary table with a status per pose: ok, fallback, check).
"""

import json
from pathlib import Path

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

from posefix.workflow.cli import run_stage, stage_parser
from posefix.io.errors import InputError
from posefix.io.files import atomic_write_bytes, write_figure
from posefix.workflow.timings import Timings
from posefix.report.figures import library_overview
from posefix.report.tables import entry_status, summary_html


def build_parser():
    return stage_parser("overview", __doc__, summary="summary.json of the library", png="overview.png to write",
                        html="summary.html to write")


def main(args, log):
    timings = Timings()
    try:
        summary = json.loads(Path(args.summary).read_text())
        library, entries = summary["library"], summary["poses"]
    except (ValueError, KeyError, TypeError) as exc:
        raise InputError(args.summary, f"not a posefix summary.json ({exc})") from None
    with timings.step("figure"):
        write_figure(args.png, library_overview(entries, title=f"posefix: {library}"))
    atomic_write_bytes(args.html, summary_html(library, entries, summary.get("failed", ())).encode())
    for entry in entries:
        kind, reason = entry_status(entry)
        if kind != "ok":
            log.info("%s: %s (%s)", entry["pose"], kind, reason)


if __name__ == "__main__":
    run_stage(build_parser(), main)
