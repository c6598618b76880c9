"""Split vertices: the seam groups of a cut sphere, weld and unweld round trips, seams that open in a pose."""

import numpy as np

from conftest import icosphere, split_along_a_seam
from posefix.mesh.weld import Weld, seam_groups


def cut(V, F):
    """The sphere split along a seam: (V', F', originals, copies)."""
    F2, shared, copies = split_along_a_seam(V, F)
    return np.vstack([V, V[shared]]), F2, shared, copies


def test_a_cut_sphere_welds_back_to_the_sphere_and_unwelds_with_closed_seams():
    V, F = icosphere(2)
    Vs, Fs, shared, copies = cut(V, F)
    group = seam_groups(Vs, Fs)
    assert np.array_equal(group[copies], shared) and np.array_equal(group[: len(V)], np.arange(len(V)))
    weld = Weld.of(Vs, Fs)
    assert weld.split and np.array_equal(weld.kept, np.arange(len(V)))
    assert np.array_equal(weld.weld(Vs), V) and np.array_equal(weld.faces(Fs), F)
    X = V * 1.3 + 0.2  # a welded pose
    out = weld.unweld(X)
    assert out.shape == Vs.shape and np.array_equal(out[copies], out[shared])  # seams closed, bit for bit
    assert len(weld.apart(out, 1e-9)) == 0


def test_an_unsplit_mesh_is_its_own_weld_and_an_opened_seam_is_found():
    V, F = icosphere(2)
    weld = Weld.of(V, F)
    assert not weld.split and np.array_equal(weld.index, np.arange(len(V))) and np.array_equal(weld.faces(F), F)
    Vs, Fs, shared, copies = cut(V, F)
    pose = Vs.copy()
    pose[copies[3]] += [0.0, 0.0, 0.05]  # the seam opens at one vertex
    assert Weld.of(Vs, Fs).apart(pose, 1e-3).tolist() == [[shared[3], copies[3]]]
