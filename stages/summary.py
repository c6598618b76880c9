"""Stage summary: one entry per pose of a library, as JSON and as a Markdown table.

Reads the metrics of every pose's artifacts (``results/<library>/<pose>/*.h5``) and the Snakemake
benchmark files, and writes ``reports/<library>/summary.json`` (schema in docs/artifacts.md) and
``summary.md`` (``posefix.report.summary``).
"""

import json
from pathlib import Path

import posefix  # noqa: F401  (runtime defaults before numpy)

from posefix.pipeline.artifacts import read_artifact
from posefix.pipeline.cli import run_stage, stage_parser
from posefix.pipeline.files import atomic_write_bytes
from posefix.pipeline.timings import benchmark_seconds
from posefix.report.summary import DOWNSTREAM_DATASETS, SUMMARY_STAGES, pose_entry, summary_markdown

METRICS = ("keyframes", "constraints", "fit", "integrate", "verify")


def build_parser():
    parser = stage_parser("summary", __doc__)
    parser.add_argument("--results", required=True, help="results/<library> folder")
    parser.add_argument("--poses", required=True, help="comma-separated pose names")
    parser.add_argument("--out", required=True, help="summary.json to write")
    parser.add_argument("--markdown", required=True, help="summary.md to write")
    return parser


def summarize_pose(results, pose):
    """The summary entry of one pose, from its artifacts and benchmark files."""
    folder = Path(results) / pose
    metrics = {stage: read_artifact(folder / f"{stage}.h5", stage, [])[1]["metrics"] for stage in METRICS}
    downstream, _ = read_artifact(folder / "downstream.h5", "downstream", list(DOWNSTREAM_DATASETS))
    seconds = {stage: benchmark_seconds(Path(results) / "benchmarks" / pose, stage) for stage in SUMMARY_STAGES}
    return pose_entry(pose, metrics, downstream, seconds)


def main(args, log):
    poses = [p for p in args.poses.split(",") if p]
    entries = [summarize_pose(args.results, pose) for pose in poses]
    library = Path(args.results).name
    atomic_write_bytes(args.out, json.dumps({"library": library, "poses": entries}, indent=1).encode())
    atomic_write_bytes(args.markdown, summary_markdown(library, entries).encode())
    for e in entries:
        log.info("%s: new intersecting faces %d, deviation V_C mean %.2g max %.2g, %.1f s", e["pose"],
                 e["intersecting_faces"]["repaired_new"], e["deviation"]["constrained_mean"],
                 e["deviation"]["constrained_max"], e["seconds_total"])


if __name__ == "__main__":
    run_stage(build_parser(), main)
