"""The repair sequence of stage verify: the reach rule, the snap, the fallback and the verify metrics."""

import re

import numpy as np

from conftest import ROOT, grid_sheet
from posefix.verify.flags import REPLACED_PASS_THROUGH, REPRODUCED
from posefix.verify.sequence import RepairSettings, repair_pose
from posefix.verify.state import RepairProblem


def _two_sheets():
    """Two parallel 11 x 11 sheets 0.1 apart, all of them V_C, and a clean problem with target = V."""
    V1, F1 = grid_sheet(11, 0.0)
    V2, F2 = grid_sheet(11, 0.1)
    V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
    empty = np.zeros((0, 2), dtype=np.int64)
    return V, F, RepairProblem.build(V, V, F, np.ones(len(V), bool), [empty, empty])


def test_constrained_vertices_within_reach_are_snapped_and_far_ones_come_from_the_target():
    V, F, problem = _two_sheets()
    d, eps = 1.0, 1e-5
    X = V.copy()
    X[:, 2] += 1e-4  # within reach: max(100 eps, 2 * fit error 1e-4) = 2e-4
    X[7, 2] += 1.0  # a spike through the upper sheet, beyond reach and the pass-through threshold 100 eps
    result = repair_pose(problem, X, d, eps, 1e-4)
    assert np.array_equal(result.X, V) and not result.new.any()
    assert result.replaced[7] == REPLACED_PASS_THROUGH  # held back by the snap, then copied from the target
    assert np.count_nonzero(result.replaced & REPRODUCED) >= len(V) - 10
    assert result.integrated["constrained_max"] > 1.0 and result.summary["constrained_max"] == 0.0
    assert result.metrics["fallback_pass_through"] >= 1


def test_the_reach_grows_with_the_fit_error():
    V, F, problem = _two_sheets()
    X = V.copy()
    X[7, 2] += 1.0
    result = repair_pose(problem, X, 1.0, 1e-5, fit_max_error_rel=1.0)  # reach max(1e-3, 2 * 1.0)
    assert np.array_equal(result.X, V) and result.replaced[7] == REPRODUCED


def test_no_snap_and_no_untangling_leave_the_integrated_pose():
    V, F, problem = _two_sheets()
    X = V + 1e-4
    result = repair_pose(problem, X, 1.0, 1e-5, 1e-4, RepairSettings(reproduce=False, repair_new=False))
    assert np.array_equal(result.X, X) and not result.replaced.any()
    assert result.deviation.max() == result.integrated_deviation.max() > 0
    assert set(result.seconds) == {"reproduce", "fallback", "verify"}


def _expand(token):
    """``a_{x,y}`` -> ``a_x``, ``a_y`` (every brace group, recursively)."""
    m = re.search(r"\{([^}]*)\}", token)
    if not m:
        return [token]
    return [name for alt in m.group(1).split(",") for name in _expand(token[:m.start()] + alt + token[m.end():])]


def test_metrics_are_the_documented_verify_metrics():
    V, F, problem = _two_sheets()
    metrics = repair_pose(problem, V, 1.0, 1e-5, 1e-4).metrics
    section = (ROOT / "docs" / "artifacts.md").read_text().split("## verify")[1].split("## export")[0]
    listed = section.split("Metrics:")[1].split("Timings:")[0]
    assert set(metrics) == {n for token in re.findall(r"`([a-z_{},0-9]+)`", listed) for n in _expand(token)}
    assert metrics["repaired_new"] == 0 and metrics["vertices"] == len(V) and metrics["faces"] == len(F)
