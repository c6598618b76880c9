"""The contact repair: key frames tracked from the reference, no new intersection whatever the key frames do."""

import numpy as np

from conftest import grid_sheet
from posefix.contact.keyframe_tracking import track_keyframes
from posefix.mesh.contact_solver import ContactSolver
from posefix.mesh.rotations import rotation_exp


def _sheets():
    """A 3 x 3 lower sheet and a unit upper sheet 0.1 above its middle (it cannot slip round its edges)."""
    V1, F1 = grid_sheet(13, 0.0)
    V1[:, :2] = 3.0 * V1[:, :2] - 1.0
    V2, F2 = grid_sheet(9, 0.1)
    return np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)]), len(V1)


def test_key_frames_that_pass_through_each_other_form_no_new_intersection():
    V, F, n1 = _sheets()
    target = V.copy()
    target[n1:, 2] = -0.1 + 0.2 * V[n1:, 0]  # the upper sheet tilted through the lower one
    t = np.linspace(0, 1, 4)[:, None, None]
    frames = (1 - t) * V + t * target
    none = np.zeros(len(F), dtype=bool)
    result = track_keyframes(ContactSolver(V, F), frames, none)
    assert not result.faces.any() and not result.new_faces.any()
    assert result.contact.any() and result.metrics["contact_vertices"] == result.contact.sum()
    assert result.X[n1:, 2].min() > result.X[:n1, 2].min()  # the upper sheet stays above the lower one
    assert result.metrics["iterations"] > 0


def test_a_rigid_motion_of_the_key_frames_comes_back_exactly():
    V, F, _ = _sheets()
    R = rotation_exp(np.array([[0.0, 0.0, 0.6]]))[0]
    frames = np.stack([V, V @ R.T + [0.5, 0, 0]])
    result = track_keyframes(ContactSolver(V, F), frames, np.zeros(len(F), dtype=bool))
    assert result.metrics["converged"] and not result.contact.any()
    assert np.abs(result.X - frames[-1]).max() < 1e-12
