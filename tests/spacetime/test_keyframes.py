"""Key frames by gradient-space interpolation: endpoints, rigid motions, scaling, lion-07 without tearing."""

import numpy as np
import pytest

from conftest import icosphere, shared_library
from posefix.mesh.geometry import bbox_diagonal, edge_lengths
from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.mesh.rotations import rotation_exp
from posefix.mesh.topology import edges
from posefix.io.meshes import read_mesh
from posefix.spacetime.keyframes import deformation_gradients, keyframes, prepare
from posefix.spacetime.keyframes import frame as frame_at


@pytest.mark.parametrize("align,unwrap", [(True, True), (False, False)])
def test_endpoints_are_reproduced(demo, align, unwrap):
    V_ref, F, poses = demo
    d = bbox_diagonal(V_ref)
    for V_tgt in poses.values():
        frames, t, interp = keyframes(V_ref, V_tgt, F, 11, align=align, unwrap=unwrap)
        assert t[0] == 0.0 and t[-1] == 1.0 and len(frames) == 11
        assert np.array_equal(frames[0], V_ref) and np.array_equal(frames[-1], V_tgt)  # as stored
        assert np.abs(frame_at(interp, 0.0) - V_ref).max() <= 1e-9 * d  # the interpolation itself
        assert np.abs(frame_at(interp, 1.0) - V_tgt).max() <= 1e-9 * d


def test_endpoints_with_several_components():
    V1, F1 = icosphere(2)
    V2, F2 = icosphere(2, centre=(3.0, 0.0, 0.0))
    V, F = np.vstack([V1, V2]), np.vstack([F1, F2 + len(V1)])
    rng = np.random.default_rng(0)
    V_tgt = V + 0.05 * rng.normal(size=V.shape)
    V_tgt[len(V1):] += [0.0, 1.0, 0.0]
    interp = prepare(V, V_tgt, F)
    d = bbox_diagonal(V)
    assert np.abs(frame_at(interp, 0.0) - V).max() <= 1e-9 * d
    assert np.abs(frame_at(interp, 1.0) - V_tgt).max() <= 1e-9 * d


@pytest.mark.parametrize("align", [True, False])
def test_rigid_rotation_gives_rigid_frames(align):
    V, F = icosphere(3)
    V = V * [1.0, 0.6, 0.3] + [0.5, 0.0, 0.0]  # an ellipsoid off the origin
    R = rotation_exp(np.array([[0.0, 0.0, np.pi / 2]]))[0]
    V_tgt = V @ R.T + [0.0, 2.0, 0.0]
    frames, t, _ = keyframes(V, V_tgt, F, 11, align=align)
    ref_len = edge_lengths(V, edges(F))
    c0, c1 = V.mean(0), V_tgt.mean(0)
    for frame, ti in zip(frames, t):
        assert np.allclose(edge_lengths(frame, edges(F)), ref_len, rtol=1e-6, atol=0)
        # and it is the reference rotated by t * 90 degrees about z
        R_t = rotation_exp(np.array([[0.0, 0.0, ti * np.pi / 2]]))[0]
        expected = (V - c0) @ R_t.T
        got = frame - frame.mean(0)
        assert np.abs(got - expected).max() <= 1e-6 * bbox_diagonal(V)
        assert np.allclose(frame.mean(0), (1 - ti) * c0 + ti * c1, atol=1e-9)


def test_pure_scaling_interpolates_linearly():
    V, F = icosphere(2)
    V = V + [0.3, -0.2, 1.0]
    frames, t, _ = keyframes(V, 2.5 * V, F, 6)
    for frame, ti in zip(frames, t):
        assert np.abs(frame - (1 - ti + 2.5 * ti) * V).max() <= 1e-9 * bbox_diagonal(V)


def test_deformation_gradients_of_similarities_and_affine_maps():
    V, F = icosphere(1)
    R = rotation_exp(np.array([[0.3, -1.1, 0.7]]))[0]
    J = deformation_gradients(V, 1.7 * V @ R.T + [1.0, 2.0, 3.0], F)
    assert np.allclose(J, 1.7 * R, atol=1e-12)  # a similarity: every face gets s R
    A = np.array([[1.2, 0.1, 0.0], [0.0, 0.9, 0.3], [0.2, 0.0, 1.1]])
    J = deformation_gradients(V, V @ A.T, F)
    for i in (1, 2):  # an affine map: both edges of every face map by A
        e = V[F[:, i]] - V[F[:, 0]]
        assert np.allclose(np.einsum("mij,mj->mi", J, e), e @ A.T, atol=1e-12)


def test_lion_07_middle_frames_do_not_tear():
    folder = shared_library("lion-poses")
    V_ref, F = read_mesh(folder / "lion-reference.obj")
    V_tgt, _ = read_mesh(folder / "lion-07.obj")

    def counts(**kw):
        frames, t, _ = keyframes(V_ref, V_tgt, F, 11, **kw)
        return t, np.array([intersecting_faces(self_intersecting_pairs(x, F), len(F)).sum() for x in frames])

    t, robust = counts()
    # endpoints 138 (reference) and 903 (target); in between the count stays at or below the
    # straight line between them: no frame tears
    line = robust[0] + t * (robust[-1] - robust[0])
    assert (robust[1:-1] <= line[1:-1]).all()
    _, naive = counts(align=False, unwrap=False)
    assert (naive[1:-1] > line[1:-1]).any()  # without care the middle frames tear (1,160 at t = 0.6)
    _, aligned_only = counts(unwrap=False)
    assert robust[1:-1].sum() < aligned_only[1:-1].sum()  # the branch unwrapping helps on top
