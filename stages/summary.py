"""Stage summary: one entry per pose of a library, as JSON and as a Markdown table.

Reads the metrics of every pose's artifacts (``results/<library>/<pose>/*.h5``) and the Snakemake
benchmark files, and writes ``reports/<library>/summary.json`` (schema in docs/artifacts.md) and
``summary.md`` (``posefix.report.summary``). With ``--repairs``, every pose's entry also compares
the other repairs (``<pose>/<name>.h5``): their intersections, and their deviation from the
target over space-time's ``V_C`` (``classify.h5``) and the rest, measured as space-time's. Every repaired pose's distortion
(worst edge-length and face-area ratios against the target and the reference, faces beyond
``--distortion-limit`` against both) is measured here too (``posefix.mesh.distortion``).
"""

import json
from functools import partial
from pathlib import Path

import posefix.workflow.interrupt  # noqa: F401  (first: Ctrl-C exits quietly; runtime defaults before numpy)

from posefix.io.artifacts import metrics_carried, read_artifact, read_repair
from posefix.mesh.distortion import distortion_summary
from posefix.workflow.cli import named_path, run_stage, stage_parser
from posefix.workflow.stage_settings import SummarySettings
from posefix.io.errors import InputError
from posefix.io.files import atomic_write_bytes
from posefix.workflow.timings import benchmark_seconds
from posefix.verify.deviation import deviation
from posefix.report.summary import DOWNSTREAM_DATASETS, SUMMARY_STAGES, repair_entry, pose_entry, summary_markdown

METRICS = ("keyframes", "fit", "verify")


def build_parser():
    parser = stage_parser("summary", __doc__, [(SummarySettings, "summary (config summary)")],
                          results="results/<library> folder", poses="comma-separated pose names",
                          out="summary.json to write", markdown="summary.md to write")
    parser.add_argument("--repairs", default="",
                        help="comma-separated other repairs to compare (their <pose>/<name>.h5), e.g. medial")
    parser.add_argument("--failed", type=named_path, action="append", default=[], metavar="POSE=ERROR",
                        help="a pose that did not finish and its error line (listed apart; the run failed)")
    return parser


def summarize_pose(results, pose, repairs=(), limit=4.0):
    """The summary entry of one pose, from its artifacts and benchmark files, with the ``repairs`` (names);
    ``limit``: the distortion limit."""
    folder = Path(results) / pose
    metrics = {stage: read_artifact(folder / f"{stage}.h5", stage, [])[1]["metrics"] for stage in METRICS}
    metrics["integrate"] = metrics_carried(metrics["verify"], "integrate")  # integrate.h5 is an intermediate
    shapes = read_artifact(folder / "keyframes.h5", "keyframes", ["reference", "target", "faces"])[0]
    repaired = read_artifact(folder / "verify.h5", "verify", ["repaired"])[0]["repaired"]
    measure = partial(distortion_summary, rests={"target": shapes["target"], "reference": shapes["reference"]},
                      F=shapes["faces"], limit=limit)
    downstream, _ = read_artifact(folder / "downstream.h5", "downstream", list(DOWNSTREAM_DATASETS))
    seconds = {stage: benchmark_seconds(Path(results) / "benchmarks" / pose, stage) for stage in SUMMARY_STAGES}
    compared = {}
    if repairs:
        mask = read_artifact(folder / "classify.h5", "classify", ["mask"])[0]["mask"].astype(bool)
        d = float(metrics["keyframes"]["bbox_diagonal"])
        target = (shapes["target"], mask, d)
        compared = {name: summarize_repair(folder / f"{name}.h5", name, target, downstream, measure)
                    for name in repairs}
        for name, entry in compared.items():  # wall seconds of the stage, as space-time's (the artifact's: in-process)
            wall = benchmark_seconds(Path(results) / "benchmarks" / pose, f"repair_{name}")
            entry["seconds"] = entry["seconds"] if wall is None else wall
    return pose_entry(pose, metrics, downstream, seconds, compared, measure(repaired))


def summarize_repair(path, name, target, downstream, measure):
    """``repairs.<name>`` of a pose's entry: the artifact's metrics, the deviation of its repaired pose from the
    target over ``V_C`` and the rest relative to ``d`` (``target``: the target (n, 3), ``V_C`` (n,) bool and ``d``),
    the downstream runs towards it, ``measure`` (its distortion summary) of the repaired pose."""
    V_tgt, mask, d = target
    data, attrs = read_repair(path, name, ["repaired"])
    if data["repaired"].shape != V_tgt.shape:
        raise InputError(path, f"repaired {data['repaired'].shape} is not {V_tgt.shape} like the pose")
    _, summary = deviation(data["repaired"], V_tgt, mask, d)
    return repair_entry(name, attrs["metrics"], summary, downstream, measure(data["repaired"]))


def main(args, log):
    poses = [p for p in args.poses.split(",") if p]
    repairs = [b for b in args.repairs.split(",") if b]
    entries = [summarize_pose(args.results, pose, repairs, args.distortion_limit) for pose in poses]
    library = Path(args.results).name
    failed = [{"pose": pose, "error": error} for pose, error in args.failed]
    summary = {"library": library, "poses": entries} | ({"failed": failed} if failed else {})
    atomic_write_bytes(args.out, json.dumps(summary, indent=1).encode())
    atomic_write_bytes(args.markdown, summary_markdown(library, entries, failed).encode())
    for e in entries:
        log.info("%s: new intersecting faces %d, deviation V_C mean %.2g max %.2g, %.1f s", e["pose"],
                 e["intersecting_faces"]["repaired_new"], e["deviation"]["constrained_mean"],
                 e["deviation"]["constrained_max"], e["seconds_total"])
        for name, b in e.get("repairs", {}).items():
            log.info("%s, %s: new intersecting faces %d, deviation V_C mean %.2g max %.2g, %.1f s", e["pose"], name,
                     b["intersecting_faces"]["repaired_new"], b["deviation"]["constrained_mean"],
                     b["deviation"]["constrained_max"], b["seconds"])


if __name__ == "__main__":
    run_stage(build_parser(), main)
