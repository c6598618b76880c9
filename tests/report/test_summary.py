"""Summary entries: from the stages' metrics and the downstream runs to summary.json and summary.md."""

import numpy as np

from posefix.report.summary import SUMMARY_STAGES, downstream_entry, pose_entry, summary_markdown


def _metrics():
    verify = {"intersecting_faces_reference": 2, "intersecting_faces_target": 40, "intersecting_faces_repaired": 3,
              "repaired_new": 1, "repaired_new_in_fallback": 1, "intersecting_faces_keyframes_max": 50,
              "fallback_vertices": 7, "fallback_pass_through": 5, "fallback_new_intersection": 2,
              "reproduced_vertices": 90, "pushed_vertices": 4}
    for prefix in ("deviation", "integrated_deviation"):
        for k in ("constrained_max", "constrained_mean", "constrained_p95", "free_max", "free_mean", "free_p95"):
            verify[f"{prefix}_{k}"] = 1e-3 if prefix == "deviation" else 2e-3
    return {"keyframes": {"vertices": 100, "faces": 196, "keyframes": 11},
            "constraints": {"constraint_vertices": 80, "constraints": 1040},
            "fit": {"centers": 400, "iterations": 5, "stop_reason": "eps", "max_error_rel": 1e-4, "rms_error_rel": 1e-5,
                    "max_condition": 1e7, "seconds": 2.0},
            "integrate": {"backend": "numpy", "device": "numpy (CPU)", "seconds": 1.0, "steps_mean": 12.5,
                          "steps_max": 20},
            "verify": verify}


def _downstream():
    """Two k_b x one alpha x two examples, stored in the stage's order (alpha, k_b, example)."""
    return {"alpha": np.array([1.0] * 4), "k_bend": np.array([0.1, 0.1, 0.01, 0.01]),
            "example": np.array([0, 1, 0, 1], dtype=np.uint8), "iterations": np.array([9, 5, 7, 3]),
            "converged": np.array([False, True, True, True]), "reason": np.array([1, 0, 0, 0], dtype=np.uint8),
            "final_error": np.array([1e-3, 0, 0, 0]), "seconds": np.array([1.0, 2.0, 3.0, 4.0])}


def test_downstream_entry_lists_runs_per_alpha_and_example_sorted_by_k_bend():
    entry = downstream_entry(_downstream())
    assert entry["k_bend"] == [0.01, 0.1] and entry["seconds"] == 10.0 and list(entry["alphas"]) == ["1"]
    assert entry["alphas"]["1"]["original"] == {"iterations": [7, 9], "converged": [True, False],
                                                "reason": ["converged", "stall"], "final_error": [0.0, 1e-3]}
    assert entry["alphas"]["1"]["repaired"]["iterations"] == [3, 5]


def test_pose_entry_and_its_markdown_row():
    seconds = dict.fromkeys(SUMMARY_STAGES, 1.5) | {"export": None}
    e = pose_entry("p-01", _metrics(), _downstream(), seconds)
    assert e["intersecting_faces"] == {"reference": 2, "target": 40, "repaired": 3, "repaired_new": 1,
                                       "repaired_new_in_fallback": 1, "keyframes_max": 50}
    assert e["fallback"] == {"pass_through": 5, "new_intersection": 2, "reproduced": 90, "pushed": 4}
    assert e["seconds_total"] == 1.5 * (len(SUMMARY_STAGES) - 1) and e["deviation"]["free_p95"] == 1e-3
    text = summary_markdown("lib", [e])
    assert text.startswith("# posefix summary: lib\n")
    assert "| p-01 | 196 | 2 / 40 / 50 / 3 | 1 (1) | 80 | 400 | eps |" in text
    assert "Integration: numpy (numpy (CPU))." in text and "## Downstream check" in text
