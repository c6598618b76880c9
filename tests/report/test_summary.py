"""Summary entries: from the stages' metrics and the downstream runs to summary.json and summary.md."""

import json

import numpy as np
import pytest

from conftest import run_stage
from posefix.io.artifacts import carried_metrics, write_artifact
from posefix.verify.deviation import deviation
from posefix.report.summary import SUMMARY_STAGES, repair_entry, downstream_entry, pose_entry, summary_markdown


def _metrics():
    verify = {"intersecting_faces_reference": 2, "intersecting_faces_target": 40, "intersecting_faces_repaired": 3,
              "repaired_new": 1, "repaired_new_in_fallback": 1, "intersecting_faces_keyframes_max": 50,
              "fallback_vertices": 7, "fallback_pass_through": 5, "fallback_new_intersection": 2,
              "reproduced_vertices": 90, "pushed_vertices": 4}
    for prefix in ("deviation", "integrated_deviation"):
        for k in ("constrained_max", "constrained_mean", "constrained_p95", "free_max", "free_mean", "free_p95"):
            verify[f"{prefix}_{k}"] = 1e-3 if prefix == "deviation" else 2e-3
    return {"keyframes": {"vertices": 100, "faces": 196, "keyframes": 11, "bbox_diagonal": 2.0},
            "fit": {"constraint_vertices": 80, "constraints": 1040,
                    "centers": 400, "iterations": 5, "stop_reason": "eps", "max_error_rel": 1e-4, "rms_error_rel": 1e-5,
                    "max_condition": 1e7, "seconds": 2.0},
            "integrate": {"backend": "numpy", "device": "numpy (CPU)", "seconds": 1.0, "steps_mean": 12.5,
                          "steps_max": 20},
            "verify": verify}


def _downstream(medial=False):
    """Two k_b x one alpha x two examples (three with ``medial``), in the stage's order (alpha, k_b, example),
    ``examples`` as read back from HDF5 (bytes)."""
    d = {"alpha": np.array([1.0] * 4), "k_bend": np.array([0.1, 0.1, 0.01, 0.01]),
         "example": np.array([0, 1, 0, 1], dtype=np.uint8), "examples": np.array([b"original", b"repaired"], object),
         "iterations": np.array([9, 5, 7, 3]), "converged": np.array([False, True, True, True]),
         "reason": np.array([1, 0, 0, 0], dtype=np.uint8), "final_error": np.array([1e-3, 0, 0, 0]),
         "seconds": np.array([1.0, 2.0, 3.0, 4.0])}
    if medial:  # runs 2 and 5 towards the medial repair: k_b 0.1 stalls, 0.01 converges in 4
        order = [0, 1, 1, 2, 3, 3]
        d = {k: (v[order] if len(v) == 4 else v) for k, v in d.items()}
        d |= {"example": np.array([0, 1, 2, 0, 1, 2], np.uint8), "examples": np.array([b"original", b"repaired",
                                                                                         b"medial"], object)}
        d["iterations"][[2, 5]], d["converged"][[2, 5]], d["reason"][[2, 5]] = [11, 4], [False, True], [1, 0]
        d["seconds"] = d["seconds"] + np.array([0, 0, 10.0, 0, 0, 20.0])
    return d


def test_downstream_entry_lists_runs_per_alpha_and_example_sorted_by_k_bend():
    entry = downstream_entry(_downstream())
    assert entry["k_bend"] == [0.01, 0.1] and entry["seconds"] == 10.0 and list(entry["alphas"]) == ["1"]
    assert entry["alphas"]["1"]["original"] == {"iterations": [7, 9], "converged": [True, False],
                                                "reason": ["converged", "stall"], "final_error": [0.0, 1e-3]}
    assert entry["alphas"]["1"]["repaired"]["iterations"] == [3, 5]


def test_downstream_entry_of_another_repair_has_s0s_shape_and_only_its_runs():
    d = _downstream(medial=True)
    assert downstream_entry(d) == downstream_entry(_downstream())  # S0's entry: its two examples, its seconds
    entry = downstream_entry(d, ("medial",))
    assert entry["k_bend"] == [0.01, 0.1] and entry["seconds"] == 4.0 + 20.0 + 2.0 + 10.0
    assert entry["alphas"] == {"1": {"medial": {"iterations": [4, 11], "converged": [True, False],
                                                "reason": ["converged", "stall"], "final_error": [0.0, 0.0]}}}


def _repair_metrics():
    return {"iterations": 12, "best": 9, "seconds": 2.5, "intersecting_faces_target": 40,
            "intersecting_faces_repaired": 6, "intersecting_faces_repaired_new": 5}


def _displaced():
    """Target, a repair moved 0.02 along z on V_C (the first 3 vertices) and 0.2 / 0.2 / 0.4 on the rest, V_C."""
    start = np.random.default_rng(0).normal(size=(6, 3))
    repaired = start + np.array([0.02, 0.02, 0.02, 0.2, 0.2, 0.4])[:, None] * [0.0, 0.0, 1.0]
    return start, repaired, np.arange(6) < 3


def test_repair_entry_measures_the_deviation_as_s0():
    start, repaired, mask = _displaced()
    _, dev = deviation(repaired, start, mask, 2.0)
    b = repair_entry("medial", _repair_metrics(), dev, _downstream())
    assert b["intersecting_faces"] == {"repaired": 6, "repaired_new": 5}
    assert b["iterations"] == 12 and b["seconds"] == 2.5 and "downstream" not in b  # not checked towards it
    assert b["deviation"]["constrained_mean"] == pytest.approx(0.01) and b["deviation"]["constrained_max"] == (
        pytest.approx(0.01))
    assert b["deviation"]["free_mean"] == pytest.approx(0.4 / 3) and b["deviation"]["free_max"] == pytest.approx(0.2)
    b = repair_entry("medial", _repair_metrics(), dev, _downstream(medial=True))
    assert b["downstream"] == downstream_entry(_downstream(medial=True), ("medial",))


def test_pose_entry_and_its_markdown_row():
    seconds = dict.fromkeys(SUMMARY_STAGES, 1.5) | {"export": None}
    e = pose_entry("p-01", _metrics(), _downstream(), seconds)
    assert e["intersecting_faces"] == {"reference": 2, "target": 40, "repaired": 3, "repaired_new": 1,
                                       "repaired_new_in_fallback": 1, "keyframes_max": 50}
    assert e["fallback"] == {"pass_through": 5, "new_intersection": 2, "reproduced": 90, "pushed": 4}
    assert e["seconds_total"] == 1.5 * (len(SUMMARY_STAGES) - 1) and e["deviation"]["free_p95"] == 1e-3
    assert "repairs" not in e
    text = summary_markdown("lib", [e])
    assert text.startswith("# posefix summary: lib\n")
    assert "| p-01 | 196 | 2 / 40 / 50 / 3 | 1 (1) | 80 | 400 | eps |" in text
    assert "Integration: numpy (numpy (CPU))." in text and "## Downstream check" in text
    assert "baseline" not in text


def test_markdown_compares_s0_with_the_other_repair_per_pose():
    start, repaired, mask = _displaced()
    d = _downstream(medial=True)
    repairs = {"medial": repair_entry("medial", _repair_metrics(), deviation(repaired, start, mask, 2.0)[1], d)}
    seconds = dict.fromkeys(SUMMARY_STAGES, 1.5)
    e = pose_entry("p-01", _metrics(), d, seconds, repairs)
    assert e["repairs"] == repairs and e == {**pose_entry("p-01", _metrics(), d, seconds), "repairs": repairs}
    lines = summary_markdown("lib", [e]).splitlines()
    at = lines.index("## Space-time vs the other repairs")
    assert lines[at + 2] == ("| pose | new faces space-time / medial | V_C dev. mean space-time / medial | V_C dev. max space-time / medial | "
                             "free dev. max space-time / medial | seconds space-time / medial | GN converged space-time / medial |")
    # S0: 1 new face, 1e-3 everywhere, 6 stages keyframes..verify x 1.5 s, 2 runs converged; medial: the above
    assert lines[at + 4] == "| p-01 | 1 / 5 | 0.001 / 0.01 | 0.001 / 0.01 | 0.001 / 0.2 | 9.0 / 2.5 | 2 / 1 |"


def _results(folder, medial=True):
    """A results/<library> folder with one pose's artifacts (metrics only where the summary reads only
    those), its benchmark files, and the medial repair of :func:`_displaced`."""
    pose = folder / "p-01"
    pose.mkdir(parents=True)
    write = {"params": {}, "inputs": [], "timings": {}}
    start, repaired, mask = _displaced()
    faces = np.array([[0, 1, 2], [3, 4, 5]])
    shapes = {"keyframes": {"reference": start, "target": start, "faces": faces}, "verify": {"repaired": start}}
    metrics = _metrics()
    metrics["verify"] |= carried_metrics(metrics.pop("integrate"), "integrate")  # integrate.h5: an intermediate
    for stage, values in metrics.items():
        write_artifact(pose / f"{stage}.h5", stage, shapes.get(stage, {}), metrics=values, **write)
    write_artifact(pose / "downstream.h5", "downstream", _downstream(medial), **write)
    write_artifact(pose / "classify.h5", "classify", {"mask": mask}, **write)
    write_artifact(pose / "medial.h5", "repair_medial", {"start": start, "repaired": repaired},
                   metrics=_repair_metrics(), **write)
    (folder / "benchmarks" / "p-01").mkdir(parents=True)
    for stage in SUMMARY_STAGES:
        (folder / "benchmarks" / "p-01" / f"{stage}.tsv").write_text("s\th:m:s\n1.5\t0:00:01\n")
    return folder


def test_summary_and_overview_stages_compare_the_other_repair(tmp_path):
    results = _results(tmp_path / "results" / "lib")
    out = tmp_path / "reports"
    out.mkdir()
    common = ["--results", results, "--poses", "p-01"]
    run_stage("summary", *common, "--repairs", "medial", "--out", out / "s.json", "--markdown", out / "s.md")
    run_stage("summary", *common, "--repairs", "", "--out", out / "plain.json", "--markdown", out / "plain.md")
    entry = json.loads((out / "s.json").read_text())["poses"][0]
    medial = entry.pop("repairs")["medial"]
    assert entry == json.loads((out / "plain.json").read_text())["poses"][0]  # S0's entry unchanged
    assert medial["intersecting_faces"] == {"repaired": 6, "repaired_new": 5} and medial["iterations"] == 12
    assert medial["deviation"]["constrained_max"] == pytest.approx(0.01)  # 0.02 / d = 2 (keyframes' diagonal)
    assert medial["deviation"]["free_max"] == pytest.approx(0.2) and medial["seconds"] == 2.5
    assert medial["downstream"]["alphas"]["1"]["medial"]["converged"] == [True, False]
    assert entry["distortion"] == {"edge_target": 1.0, "area_target": 1.0, "edge_reference": 1.0,
                                   "area_reference": 1.0, "edge_nearest": 1.0, "faces_over": 0, "faces_severe": 0,
                                   "limit": 4.0}  # S0's repair: the target
    assert medial["distortion"]["edge_target"] > 1.0 and medial["distortion"]["limit"] == 4.0
    assert "| p-01 | 1 / 5 | 0.001 / 0.01 |" in (out / "s.md").read_text()
    assert "Space-time vs the other" not in (out / "plain.md").read_text()
    run_stage("overview", "--summary", out / "s.json", "--png", out / "o.png", "--html", out / "o.html")
    page = (out / "o.html").read_text()
    assert "<th>new faces space-time / medial</th>" in page and "<td>1 / 5</td><td>0.001 / 0.01</td>" in page
    assert (out / "o.png").stat().st_size > 10_000
