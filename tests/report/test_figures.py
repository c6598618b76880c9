"""Report figures: camera, renders that show what they claim, the library status."""

import numpy as np

from conftest import icosphere, pixels
from posefix.report import figures
from posefix.report.rasterizer import camera


def test_pose_figures_are_non_blank():
    V, F = icosphere(2)
    R = camera(V)
    X = V * 1.01
    faces = np.zeros(len(F), bool)
    faces[:10] = True
    history = {"centers": np.array([128, 256, 384]), "max_error": np.array([1e-2, 5e-3, 1e-3]),
               "rms_error": np.array([1e-3, 5e-4, 1e-4]), "condition": np.array([1e3, 1e5, 1e6]),
               "seconds_evaluate": np.ones(3), "seconds_select": np.ones(3), "seconds_update": np.ones(3)}
    made = [figures.renders(F, R, {"target": (V, faces), "repaired": (X, faces)}, ~faces),
            figures.deviation_map(X, F, R, np.linalg.norm(X - V, axis=1), np.zeros(len(V), np.uint8)),
            figures.classification(V, F, R, V[:, 0] > 0, [0, 5, 10], 3, 0),
            figures.fit_history(history, 2.0, 1e-4),
            figures.timings({"fit": 2.0, "integrate": 1.0, "verify": None})]
    for fig in made:
        assert pixels(fig).var() > 0


def test_downstream_history_draws_every_run():
    runs = [{"alpha": a, "k_bend": k, "example": ex, "errors": np.geomspace(10.0, 1e-20 if c else 1.0, 8),
             "converged": c, "reason": "converged" if c else "collapsed triangle"}
            for a in (0.5, 1.0) for k in (1e-3, 1e-2) for ex, c in (("original", False), ("repaired", True))]
    runs[-1]["errors"] = np.array([3.0, 0.0])  # zero energy is drawn (clipped), not dropped
    fig = figures.downstream_history(runs, title="x")
    assert len(fig.axes) == 2 and all(len(ax.get_lines()) == 8 for ax in fig.axes)
    assert pixels(fig).var() > 0


def test_renders_show_a_panel_per_repair_on_one_scale():
    V, F = icosphere(2)
    R = camera(V)
    faces, none = np.zeros(len(F), bool), np.zeros(len(F), bool)
    faces[:10] = True
    two = figures.renders(F, R, {"target": (V, faces), "repaired": (V * 1.01, none)}, none)
    three = figures.renders(F, R, {"target": (V, faces), "space-time": (V * 1.01, none), "medial": (V * 1.5, faces)},
                            none)
    assert len(two.axes) == 2 and len(three.axes) == 3
    assert [ax.get_title() for ax in three.axes] == ["target: 10 intersecting faces, 10 not in the reference",
                                                     "space-time: 0 intersecting faces, 0 new",
                                                     "medial: 10 intersecting faces, 10 new"]
    assert two.axes[1].get_title().startswith("repaired: ")
    assert three.get_figwidth() == 1.5 * two.get_figwidth()
    assert three.axes[0].get_xlim() == three.axes[2].get_xlim()  # one scale: the larger medial pose fits
    assert pixels(three).var() > 0


def test_downstream_history_draws_other_repairs_dotted():
    runs = [{"alpha": 1.0, "k_bend": 1e-2, "example": ex, "errors": np.geomspace(10.0, 1e-3, 4), "converged": True,
             "reason": "converged"} for ex in ("original", "repaired", "medial")]
    fig = figures.downstream_history(runs, title="x")
    styles = {line.get_label().split(",")[0]: line.get_linestyle() for line in fig.axes[0].get_lines()
              if not line.get_label().startswith("_")}
    assert styles == {"original": "--", "repaired": "-", "medial": ":"}
    assert "dotted: medial" in fig.get_suptitle()



def test_renders_draw_distorted_faces_in_their_own_colour():
    V, F = icosphere(2)
    R = camera(V)
    none = np.zeros(len(F), dtype=bool)
    bad = none.copy()
    bad[: len(F) // 2] = True
    poses = {"target": (V, none), "space-time": (V, none), "contact": (V, none)}
    plain = figures.renders(F, R, poses, none)
    marked = figures.renders(F, R, poses, none, distorted=[none, bad])
    assert marked.axes[2].get_title() == f"contact: 0 intersecting faces, 0 new, {len(F) // 2} distorted"
    assert marked.axes[1].get_title() == "space-time: 0 intersecting faces, 0 new"
    a, b = pixels(plain)[..., :3], pixels(marked)[..., :3]
    purple = lambda p: ((p[..., 2] > p[..., 1] + 0.2) & (p[..., 0] > p[..., 1] + 0.1)).sum()  # noqa: E731
    assert a.shape == b.shape and purple(b) > 1000 > 10 * purple(a)
