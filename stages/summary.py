"""Stage summary: one entry per pose of a library, as JSON and as a Markdown table.

Reads the artifacts of every pose (``results/<library>/<pose>/*.h5``) and the Snakemake benchmark
files, and writes ``reports/<library>/summary.json`` (schema in docs/artifacts.md) and
``summary.md``.
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "lib"))

import json  # noqa: E402

import posefix  # noqa: E402,F401  (runtime defaults before numpy)
import numpy as np  # noqa: E402

from posefix.cli import run_stage, stage_parser  # noqa: E402
from posefix.h5io import read_artifact  # noqa: E402
from posefix.io import atomic_write_bytes, benchmark_seconds  # noqa: E402
from posefix.shells import EXAMPLES, STOP_REASONS  # noqa: E402
from posefix.tables import downstream_markdown  # noqa: E402


DEVIATIONS = ("constrained_max", "constrained_mean", "constrained_p95", "free_max", "free_mean", "free_p95")
STAGES = ("keyframes", "classify", "constraints", "fit", "integrate", "verify", "export", "downstream")


def build_parser():
    parser = stage_parser("summary", __doc__)
    parser.add_argument("--results", required=True, help="results/<library> folder")
    parser.add_argument("--poses", required=True, help="comma-separated pose names")
    parser.add_argument("--out", required=True, help="summary.json to write")
    parser.add_argument("--markdown", required=True, help="summary.md to write")
    return parser


def pose_entry(results, pose):
    """The summary entry of one pose (see docs/artifacts.md)."""
    folder = Path(results) / pose
    kf = read_artifact(folder / "keyframes.h5", "keyframes", [])[1]["metrics"]
    co = read_artifact(folder / "constraints.h5", "constraints", [])[1]["metrics"]
    fi = read_artifact(folder / "fit.h5", "fit", [])[1]["metrics"]
    it = read_artifact(folder / "integrate.h5", "integrate", [])[1]["metrics"]
    ve = read_artifact(folder / "verify.h5", "verify", [])[1]["metrics"]
    seconds = {stage: benchmark_seconds(Path(results) / "benchmarks" / pose, stage) for stage in STAGES}
    return {
        "pose": pose, "vertices": int(kf["vertices"]), "faces": int(kf["faces"]), "keyframes": int(kf["keyframes"]),
        "intersecting_faces": {
            "reference": int(ve["intersecting_faces_reference"]), "target": int(ve["intersecting_faces_target"]),
            "repaired": int(ve["intersecting_faces_repaired"]), "repaired_new": int(ve["repaired_new"]),
            "repaired_new_in_fallback": int(ve["repaired_new_in_fallback"]),
            "keyframes_max": int(ve["intersecting_faces_keyframes_max"])},
        "constraint_vertices": int(co["constraint_vertices"]), "constraints": int(co["constraints"]),
        "fit": {"centers": int(fi["centers"]), "iterations": int(fi["iterations"]), "stop_reason": str(fi["stop_reason"]),
                "max_error_rel": float(fi["max_error_rel"]), "rms_error_rel": float(fi["rms_error_rel"]),
                "max_condition": float(fi["max_condition"]), "seconds": float(fi["seconds"])},
        "integrate": {"backend": str(it["backend"]), "device": str(it["device"]), "seconds": float(it["seconds"]),
                      "steps_mean": float(it["steps_mean"]), "steps_max": int(it["steps_max"])},
        "deviation": {k: float(ve[f"deviation_{k}"]) for k in DEVIATIONS},
        "integrated_deviation": {k: float(ve[f"integrated_deviation_{k}"]) for k in DEVIATIONS},
        "fallback_vertices": int(ve["fallback_vertices"]),
        "fallback": {"pass_through": int(ve["fallback_pass_through"]),
                     "new_intersection": int(ve["fallback_new_intersection"]),
                     "reproduced": int(ve["reproduced_vertices"]), "pushed": int(ve["pushed_vertices"])},
        "downstream": downstream_entry(folder / "downstream.h5"),
        "seconds_stages": seconds,
        "seconds_total": sum(v for v in seconds.values() if v is not None),
    }


def downstream_entry(path):
    """``downstream`` of a summary entry: per alpha and example, lists over k_b (docs/artifacts.md)."""
    d, _ = read_artifact(path, "downstream", ["alpha", "k_bend", "example", "iterations", "converged", "reason",
                                              "final_error", "seconds"])
    entry = {"k_bend": sorted(set(d["k_bend"].tolist())), "alphas": {}, "seconds": float(d["seconds"].sum())}
    for alpha in sorted(set(d["alpha"].tolist())):
        per = entry["alphas"][f"{alpha:g}"] = {}
        for example, name in enumerate(EXAMPLES):
            runs = [i for i in np.flatnonzero((d["alpha"] == alpha) & (d["example"] == example))]
            runs.sort(key=lambda i: d["k_bend"][i])
            per[name] = {"iterations": [int(d["iterations"][i]) for i in runs],
                         "converged": [bool(d["converged"][i]) for i in runs],
                         "reason": [STOP_REASONS[d["reason"][i]] for i in runs],
                         "final_error": [float(d["final_error"][i]) for i in runs]}
    return entry


def markdown(library, entries):
    head = ("| pose | faces | intersecting: reference / target / keyframes max / repaired | new (in fallback) | "
            "V_C | centres | fit stop | max error / d | max kappa | fit s | integrate s | steps | "
            "deviation V_C mean / max | (integrated) | free mean / max | fallback vertices | total s |")
    lines = [f"# posefix summary: {library}", "", head,
             "|---|---:|---|---|---:|---:|---|---:|---:|---:|---:|---:|---|---|---|---:|---:|"]
    for e in entries:
        i, f, it, dv, di = (e["intersecting_faces"], e["fit"], e["integrate"], e["deviation"],
                            e["integrated_deviation"])
        lines.append(
            f"| {e['pose']} | {e['faces']} | {i['reference']} / {i['target']} / {i['keyframes_max']} / {i['repaired']} | "
            f"{i['repaired_new']} ({i['repaired_new_in_fallback']}) | {e['constraint_vertices']} | {f['centers']} | "
            f"{f['stop_reason']} | {f['max_error_rel']:.2g} | {f['max_condition']:.2g} | {f['seconds']:.1f} | "
            f"{it['seconds']:.2f} | {it['steps_mean']:.1f} | {dv['constrained_mean']:.2g} / {dv['constrained_max']:.2g} | "
            f"({di['constrained_mean']:.2g} / {di['constrained_max']:.2g}) | "
            f"{dv['free_mean']:.2g} / {dv['free_max']:.2g} | {e['fallback_vertices']} | {e['seconds_total']:.1f} |")
    backends = sorted({f"{e['integrate']['backend']} ({e['integrate']['device']})" for e in entries})
    lines += ["", f"Integration: {', '.join(backends)}. Deviations are relative to the reference's bbox diagonal; "
              "'new' counts faces intersecting in the repaired pose but not in the reference, in brackets those "
              "inside regions copied from the target (pass-through fallback, S0 Fig. 9); '(integrated)' is the "
              "deviation of the integrated pose, before the fallback and the reproduction of V_C."]
    lines += ["", "## Downstream check: Gauss-Newton discrete shells (S0 §5)", "",
              *downstream_markdown(entries), "",
              "Example-driven deformation (Froehlich & Botsch 2011) from the reference towards the original target and "
              "towards the repaired pose, over the grid of alpha x k_b in config downstream; 'fewer': iteration "
              "reduction over the settings where both converged."]
    return "\n".join(lines) + "\n"


def main(args, log):
    poses = [p for p in args.poses.split(",") if p]
    entries = [pose_entry(args.results, pose) for pose in poses]
    library = Path(args.results).name
    atomic_write_bytes(args.out, json.dumps({"library": library, "poses": entries}, indent=1).encode())
    atomic_write_bytes(args.markdown, markdown(library, entries).encode())
    for e in entries:
        log.info("%s: new intersecting faces %d, deviation V_C mean %.2g max %.2g, %.1f s", e["pose"],
                 e["intersecting_faces"]["repaired_new"], e["deviation"]["constrained_mean"],
                 e["deviation"]["constrained_max"], e["seconds_total"])


if __name__ == "__main__":
    run_stage(build_parser(), main)
