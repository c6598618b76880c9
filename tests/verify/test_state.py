"""The repair problem and state: new faces, trials that improve, copies that do not share flags."""

import numpy as np

from conftest import icosphere
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.verify.state import RepairProblem, RepairState


def _two_spheres(gap):
    V1, F1 = icosphere(2)
    V2, F2 = icosphere(2, centre=(2.0 + gap, 0.0, 0.0))
    return np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)]), len(V1)


def test_problem_derives_adjacency_and_the_end_frames_faces():
    V, F, _ = _two_spheres(-0.2)
    pairs = self_intersecting_pairs(V, F)
    empty = np.zeros((0, 2), dtype=np.int64)
    p = RepairProblem.build(V, V, F, np.ones(len(V), bool), [empty, pairs])
    assert not p.reference_faces.any() and np.array_equal(p.target_faces, intersecting_faces(pairs, len(F)))
    assert p.A.shape == (len(V), len(V)) and (p.A != p.A.T).nnz == 0 and p.A.diagonal().sum() == 0


def test_a_trial_that_removes_new_faces_improves_and_is_flagged_on_accept():
    V, F, n1 = _two_spheres(-0.2)  # intersecting
    state = RepairState(V, F, np.zeros(len(F), dtype=bool))
    assert state.new.sum() > 0
    apart = V.copy()
    apart[n1:, 0] += 0.5
    region = np.arange(n1, len(V))
    trial = state.trial(region, apart)
    assert state.improves(trial) and not trial[2].any()
    copy = state.copy()
    copy.accept(trial, region, 4)
    assert (copy.replaced[region] == 4).all() and not state.replaced.any() and state.new.sum() > 0
    assert not state.improves(state.trial(region, V))  # no change: nothing removed


def test_faces_of_the_reference_are_never_new():
    V, F, _ = _two_spheres(-0.2)
    reference = intersecting_faces(self_intersecting_pairs(V, F), len(F))
    assert not RepairState(V, F, reference).new.any()
