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
    made = [figures.renders(V, X, F, R, faces, faces, ~faces),
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
