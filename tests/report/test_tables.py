"""Library tables: pose status, downstream tallies, the HTML summary."""

from conftest import pixels
from posefix.report import figures
from posefix.report.tables import pose_status, summary_html


def _entry(pose, new=0, inside=0, vc_max=1e-3, fallback=0, pass_through=0):
    entry = {"pose": pose, "faces": 10000, "intersecting_faces": {"reference": 0, "target": 50, "keyframes_max": 50, "repaired": new,
                                                  "repaired_new": new, "repaired_new_in_fallback": inside},
            "constraint_vertices": 10, "deviation": {"constrained_mean": 1e-4, "constrained_max": vc_max,
                                                      "free_mean": 1e-2, "free_max": 5e-2},
            "fit": {"centers": 4000, "max_error_rel": 1e-2, "max_condition": 1e8, "seconds": 5.0},
            "integrate": {"seconds": 1.0}, "fallback_vertices": fallback,
            "fallback": {"pass_through": pass_through, "new_intersection": fallback - pass_through},
            "seconds_total": 9.0, "seconds_stages": {"fit": 5.0, "integrate": 1.0}}
    kind, reason = pose_status(entry)
    return entry | {"status": {"kind": kind, "reason": reason}}


def test_pose_status_flags_what_needs_a_look():
    assert pose_status(_entry("a")) == ("ok", "")
    assert pose_status(_entry("b", new=4, inside=4, fallback=30, pass_through=30))[0] == "fallback"
    kind, reason = pose_status(_entry("c", new=6, inside=4))
    assert kind == "check" and "2 new intersecting faces" in reason
    kind, reason = pose_status(_entry("d", vc_max=1.5e-3))
    assert kind == "check" and "V_C max deviation" in reason


def test_the_status_flags_severe_or_widespread_distortion_and_not_one_crushed_face():
    def distorted(over, severe):
        return {**_entry("e"), "distortion": {"edge_target": 11.9, "area_target": 5.0, "edge_reference": 11.0,
                                              "area_reference": 4.5, "faces_over": over, "faces_severe": severe,
                                              "limit": 4.0}}
    assert pose_status(distorted(10, 0)) == ("ok", "")  # 0.1% of 10,000 faces: noise
    kind, reason = pose_status(distorted(11, 0))  # no new intersection, yet not ok
    assert kind == "check" and reason == "11 faces (0.11%) stretched or crushed beyond 4x"
    assert pose_status(distorted(1, 1)) == ("check", "1 faces stretched or crushed beyond 10x")


def test_a_contact_finish_that_fell_back_or_did_not_converge_is_never_ok():
    entry = _entry("f")
    assert pose_status(entry | {"finish": {"converged": True, "reverted": False}}) == ("ok", "")
    kind, reason = pose_status(entry | {"finish": {"converged": True, "reverted": True}})
    assert kind == "check" and "fell back to the path lines" in reason
    assert pose_status(entry | {"finish": {"converged": False, "reverted": False}}) == (
        "check", "the contact finish did not converge")


def test_the_contact_finish_taking_the_target_where_it_undoes_the_references_intersections_is_ok():
    finish = {"finish": {"converged": True, "reverted": False}}
    assert pose_status(_entry("g", fallback=73) | finish) == (
        "ok", "73 vertices take the target, which undoes the reference's own intersections there")
    assert pose_status(_entry("g", fallback=73))[0] == "fallback"  # the snap finish's untangling
    assert pose_status(_entry("h", fallback=30, pass_through=30) | finish)[0] == "fallback"


def test_the_page_reads_the_stored_status():
    page = summary_html("lib", [_entry("a") | {"status": {"kind": "check", "reason": "stored"}}])
    assert "check: stored" in page and "0 ok, 0 fallback, 1 check" in page


def test_summary_page_and_figure():
    page = summary_html("lib <x>", [_entry("a"), _entry("c", new=6, inside=4)])
    assert page.count("<tr style=") == 2 and "lib &lt;x&gt;" in page and "1 ok, 0 fallback, 1 check" in page
    assert "<a href='viewer.html'>3D viewer</a>" in page
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


def _with_medial(entry, new, vc_max, seconds, converged=None):
    """``entry`` with the medial repair beside it (``converged``: its converged runs at k_b 1e-3, 1e-2, 1e-1)."""
    medial = {"intersecting_faces": {"repaired": new, "repaired_new": new}, "iterations": 10, "seconds": seconds,
              "deviation": {"constrained_mean": vc_max / 2, "constrained_max": vc_max, "free_mean": 0.1,
                            "free_max": 0.3}}
    if converged is not None:
        medial["downstream"] = {"k_bend": [1e-3, 1e-2, 1e-1], "seconds": 1.0, "alphas": {"1": {"medial": {
            "iterations": [9] * 3, "converged": converged, "final_error": [0.0] * 3, "reason": ["stall"] * 3}}}}
    return {**entry, "repairs": {"medial": medial}}


def test_the_comparison_puts_s0_and_the_other_repair_side_by_side():
    from posefix.report.tables import comparison_table, compared_repairs
    a = _with_medial(_entry("a", new=2), new=7, vc_max=2e-2, seconds=3.25)
    assert compared_repairs(a, ["medial"]) == {
        "space-time": {"new": 2, "constrained_mean": 1e-4, "constrained_max": 1e-3, "free_max": 5e-2, "seconds": 6.0,
                       "converged": None, "edge": None, "distorted": None},  # its seconds: keyframes to verify (5 + 1)
        "medial": {"new": 7, "constrained_mean": 1e-2, "constrained_max": 2e-2, "free_max": 0.3, "seconds": 3.25,
                   "converged": None, "edge": None, "distorted": None}}
    header, rows = comparison_table([a])
    assert header == ["pose", "new faces space-time / medial", "V_C dev. mean space-time / medial",
                      "V_C dev. max space-time / medial", "free dev. max space-time / medial",
                      "seconds space-time / medial"]  # no GN column without the check
    assert rows == [["a", "2 / 7", "0.0001 / 0.01", "0.001 / 0.02", "0.05 / 0.3", "6.0 / 3.2"]]
    assert comparison_table([_entry("a")]) == ([], [])
    measured = {"edge_target": 2.5, "area_target": 3.0, "edge_reference": 2.0, "area_reference": 2.0, "limit": 4.0}
    a["distortion"], a["repairs"]["medial"]["distortion"] = measured | {"faces_over": 0}, measured | {"faces_over": 3}
    header, rows = comparison_table([a])
    assert header[5:7] == ["worst edge ratio space-time / medial", "distorted faces space-time / medial"]
    assert rows[0][5:7] == ["2.5 / 2.5", "0 / 3"]
    page = summary_html("lib", [a])
    assert "<h3>Space-time vs the other repairs</h3>" in page and "<td>2 / 7</td>" in page
    assert "GN converged" not in page.split("<h3>")[1]  # neither as a column nor in the note
    assert "Space-time vs the other" not in summary_html("lib", [_entry("a")])


def test_the_comparison_counts_converged_runs_towards_each_repair():
    from posefix.report.tables import comparison_note, comparison_table
    e = {**_entry("a"), "downstream": _downstream([40, 50, 200], [True, True, False], [20, 30, 25],
                                                   [True, False, True])}
    header, rows = comparison_table([_with_medial(e, 0, 1e-3, 1.0, converged=[True, False, False])])
    assert header[-1] == "GN converged space-time / medial" and rows[0][-1] == "2 / 1"
    assert "'GN converged': Gauss-Newton runs" in comparison_note(header)


def test_library_overview_draws_the_other_repair_beside_s0():
    e = {**_entry("a"), "downstream": _downstream([40, 50, 200], [True, True, False], [20, 30, 25],
                                                   [True, False, True])}
    entries = [_with_medial(e, 4, 1e-3, 2.0, converged=[True, True, False]),
               _with_medial({**e, "pose": "b"}, 0, 1e-2, 5.0, converged=[False, False, False])]
    fig = figures.library_overview(entries)
    assert len(fig.axes) == 6 and pixels(fig).var() > 0
    faces, deviations, _, seconds, converged, _ = fig.axes
    labels = [t.get_text() for t in faces.get_legend().get_texts()]
    assert labels == ["target", "space-time: new", "space-time: new, in pass-through", "medial: new"]
    medial_bars = faces.containers[-1]
    assert [b.get_height() for b in medial_bars] == [4, 0]
    assert [line.get_label() for line in deviations.get_lines()][3:6] == ["medial V_C max", "medial V_C mean",
                                                                          "medial free max"]
    assert [b.get_height() for b in seconds.containers[-1]] == [2.0, 5.0]
    assert [b.get_height() for b in converged.containers[-1]] == [2, 0]  # runs converged towards medial
    assert [t.get_text() for t in converged.get_legend().get_texts()] == ["runs per example", "original target",
                                                                          "space-time", "medial"]
