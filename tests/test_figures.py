"""Report figures: camera, renders that show what they claim, the library status."""

import io

import numpy as np
from matplotlib.figure import Figure
from matplotlib.image import imread

from conftest import icosphere
from posefix import figures
from posefix.render import HIGHLIGHT, camera, draw_mesh, view_limits
from posefix.tables import pose_status, summary_html


def _pixels(fig):
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return imread(io.BytesIO(buffer.getvalue()))[..., :3]


def test_camera_is_a_rotation_looking_across_the_thinnest_side():
    V = np.random.default_rng(0).random((50, 3)) * [1.0, 3.0, 0.2]  # thinnest along z
    R = camera(V, azimuth=0.0, elevation=0.0)
    assert np.allclose(R @ R.T, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0)
    assert np.allclose(np.abs(R[2]), [0, 0, 1])  # looks along z
    assert np.allclose(R[1], [0, 1, 0])  # y up
    R = camera(V * [1, 0.01, 1], azimuth=0.0, elevation=0.0)  # thinnest along y: z is up
    assert np.allclose(np.abs(R[2]), [0, 1, 0]) and np.allclose(R[1], [0, 0, 1])


def test_view_limits_contain_every_mesh():
    V, _ = icosphere(1)
    R = camera(V)
    limits = view_limits(V, V + [5.0, 0.0, 0.0], R=R)
    P = np.concatenate([V, V + [5.0, 0.0, 0.0]]) @ R[:2].T
    assert (P >= limits[:, 0]).all() and (P <= limits[:, 1]).all()


def test_highlighted_faces_are_visible_even_behind_the_surface():
    V, F = icosphere(2)
    R = camera(V, azimuth=0.0, elevation=0.0)
    back = (V[F].mean(axis=1) @ R[2]) < -0.5  # faces on the far side of the sphere
    plain, marked = Figure(figsize=(3, 3), dpi=60), Figure(figsize=(3, 3), dpi=60)
    draw_mesh(plain.add_subplot(), V, F, R)
    draw_mesh(marked.add_subplot(), V, F, R, highlight=[(back, HIGHLIGHT)])
    a, b = _pixels(plain), _pixels(marked)
    assert a.var() > 0
    red = (b[..., 0] > 0.6) & (b[..., 1] < 0.5) & (b[..., 2] < 0.5)
    assert red.sum() > 50 and not ((a[..., 0] > 0.6) & (a[..., 1] < 0.5)).any()


def test_pose_figures_are_non_blank():
    V, F = icosphere(2)
    R = camera(V)
    X = V * 1.01
    faces = np.zeros(len(F), bool)
    faces[:10] = True
    history = {"centers": np.array([128, 256, 384]), "max_error": np.array([1e-2, 5e-3, 1e-3]),
               "rms_error": np.array([1e-3, 5e-4, 1e-4]), "condition": np.array([1e3, 1e5, 1e6]),
               "seconds_evaluate": np.ones(3), "seconds_select": np.ones(3), "seconds_update": np.ones(3)}
    made = [figures.renders(V, X, F, R, faces, faces, ~faces),
            figures.deviation_map(X, F, R, np.linalg.norm(X - V, axis=1), np.zeros(len(V), np.uint8)),
            figures.classification(V, F, R, V[:, 0] > 0, [0, 5, 10], 3, 0),
            figures.fit_history(history, 2.0, 1e-4),
            figures.timings({"fit": 2.0, "integrate": 1.0, "verify": None})]
    for fig in made:
        assert _pixels(fig).var() > 0


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
    assert _pixels(figures.library_overview([_entry("a"), _entry("c", new=6, inside=4)])).var() > 0


def _downstream(iterations_original, converged_original, iterations_repaired, converged_repaired):
    """A summary entry's ``downstream`` with one alpha and the runs given per k_b."""
    def runs(iterations, converged):
        return {"iterations": iterations, "converged": converged, "final_error": [0.0] * len(iterations),
                "reason": ["converged" if c else "stall" for c in converged]}
    return {"k_bend": [1e-3, 1e-2, 1e-1][:len(iterations_original)], "seconds": 1.0,
            "alphas": {"1": {"original": runs(iterations_original, converged_original),
                             "repaired": runs(iterations_repaired, converged_repaired)}}}


def test_downstream_counts_compare_only_runs_where_both_converged():
    from posefix.tables import downstream_counts, downstream_markdown
    e = {**_entry("a"), "downstream": _downstream([40, 50, 200], [True, True, False], [20, 30, 25],
                                                   [True, False, True])}
    c = downstream_counts(e)
    assert c["runs"] == 3 and c["converged_original"] == 2 and c["converged_repaired"] == 2
    assert (c["iterations_original"], c["iterations_repaired"]) == (290, 75)
    assert (c["paired"], c["paired_original"], c["paired_repaired"]) == (1, 40, 20)  # only k_b 1e-3
    lines = downstream_markdown([e, e])
    assert lines[2].endswith("| 1 | 40 / 20 | 50% |") and lines[-1].startswith("| **all** | 6 | 4 | 4 |")
    fig = figures.library_overview([e, {**_entry("b"), "downstream": _downstream([9], [False], [5], [True])}])
    assert len(fig.axes) == 6 and _pixels(fig).var() > 0


def test_downstream_history_draws_every_run():
    runs = [{"alpha": a, "k_bend": k, "example": ex, "errors": np.geomspace(10.0, 1e-20 if c else 1.0, 8),
             "converged": c, "reason": "converged" if c else "collapsed triangle"}
            for a in (0.5, 1.0) for k in (1e-3, 1e-2) for ex, c in (("original", False), ("repaired", True))]
    runs[-1]["errors"] = np.array([3.0, 0.0])  # zero energy is drawn (clipped), not dropped
    fig = figures.downstream_history(runs, title="x")
    assert len(fig.axes) == 2 and all(len(ax.get_lines()) == 8 for ax in fig.axes)
    assert _pixels(fig).var() > 0
