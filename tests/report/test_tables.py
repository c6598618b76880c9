"""Library tables: pose status, downstream tallies, the HTML summary."""

from conftest import pixels
from posefix.report import figures
from posefix.report.tables import pose_status, summary_html


def _entry(pose, new=0, inside=0, vc_max=1e-3, fallback=0, pass_through=0):
    return {"pose": pose, "intersecting_faces": {"reference": 0, "target": 50, "keyframes_max": 50, "repaired": new,
                                                  "repaired_new": new, "repaired_new_in_fallback": inside},
            "constraint_vertices": 10, "deviation": {"constrained_mean": 1e-4, "constrained_max": vc_max,
                                                      "free_mean": 1e-2, "free_max": 5e-2},
            "fit": {"centers": 4000, "max_error_rel": 1e-2, "max_condition": 1e8, "seconds": 5.0},
            "integrate": {"seconds": 1.0}, "fallback_vertices": fallback,
            "fallback": {"pass_through": pass_through, "new_intersection": fallback - pass_through},
            "seconds_total": 9.0, "seconds_stages": {"fit": 5.0, "integrate": 1.0}}


def test_pose_status_flags_what_needs_a_look():
    assert pose_status(_entry("a")) == ("ok", "")
    assert pose_status(_entry("b", new=4, inside=4, fallback=30, pass_through=30))[0] == "fallback"
    kind, reason = pose_status(_entry("c", new=6, inside=4))
    assert kind == "check" and "2 new intersecting faces" in reason
    kind, reason = pose_status(_entry("d", vc_max=8e-3))
    assert kind == "check" and "V_C max deviation" in reason
    page = summary_html("lib <x>", [_entry("a"), _entry("c", new=6, inside=4)])
    assert page.count("<tr style=") == 2 and "lib &lt;x&gt;" in page and "1 ok, 0 fallback, 1 check" in page
    assert pixels(figures.library_overview([_entry("a"), _entry("c", new=6, inside=4)])).var() > 0


def _downstream(iterations_original, converged_original, iterations_repaired, converged_repaired):
    """A summary entry's ``downstream`` with one alpha and the runs given per k_b."""
    def runs(iterations, converged):
        return {"iterations": iterations, "converged": converged, "final_error": [0.0] * len(iterations),
                "reason": ["converged" if c else "stall" for c in converged]}
    return {"k_bend": [1e-3, 1e-2, 1e-1][:len(iterations_original)], "seconds": 1.0,
            "alphas": {"1": {"original": runs(iterations_original, converged_original),
                             "repaired": runs(iterations_repaired, converged_repaired)}}}


def test_downstream_counts_compare_only_runs_where_both_converged():
    from posefix.report.tables import downstream_counts, downstream_markdown
    e = {**_entry("a"), "downstream": _downstream([40, 50, 200], [True, True, False], [20, 30, 25],
                                                   [True, False, True])}
    c = downstream_counts(e)
    assert c["runs"] == 3 and c["converged_original"] == 2 and c["converged_repaired"] == 2
    assert (c["iterations_original"], c["iterations_repaired"]) == (290, 75)
    assert (c["paired"], c["paired_original"], c["paired_repaired"]) == (1, 40, 20)  # only k_b 1e-3
    lines = downstream_markdown([e, e])
    assert lines[2].endswith("| 1 | 40 / 20 | 50% |") and lines[-1].startswith("| **all** | 6 | 4 | 4 |")
    fig = figures.library_overview([e, {**_entry("b"), "downstream": _downstream([9], [False], [5], [True])}])
    assert len(fig.axes) == 6 and pixels(fig).var() > 0
