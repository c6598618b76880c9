"""Key frames on disk (posefix.io.keyframes): float32 offsets from the linear blend, the endpoints exact."""

import h5py
import numpy as np

from conftest import icosphere
from posefix.io.artifacts import write_artifact
from posefix.io.keyframes import frame_offsets, frames_from_offsets, read_keyframes, stored_frames
from posefix.mesh.geometry import bbox_diagonal
from posefix.mesh.rotations import rotation_exp


def _turning_frames(count=11):
    """A ball turning a quarter turn about z while it moves by 3 along y: frames far off the linear blend."""
    V, _ = icosphere(2)
    t = np.linspace(0.0, 1.0, count)
    frames = np.stack([V @ rotation_exp(np.array([[0.0, 0.0, ti * np.pi / 2]]))[0].T + [0.0, 3.0 * ti, 0.0]
                       for ti in t])
    return frames, t


def test_a_frame_on_the_blend_has_zero_offsets_and_one_off_it_its_difference():
    V_ref, V_tgt = np.zeros((2, 3)), np.array([[2.0, 0.0, 0.0], [0.0, 4.0, 0.0]])
    frames = np.stack([V_ref, 0.5 * V_tgt + [0.0, 0.0, 0.25], V_tgt])
    offsets = frame_offsets(frames, [0.0, 0.5, 1.0], V_ref, V_tgt)
    assert offsets.dtype == np.float32 and offsets.shape == (1, 2, 3)
    assert np.array_equal(offsets[0], [[0.0, 0.0, 0.25], [0.0, 0.0, 0.25]])
    assert np.array_equal(frames_from_offsets(offsets, [0.0, 0.5, 1.0], V_ref, V_tgt), frames)  # exact in float32


def test_stored_frames_are_within_float32_rounding_and_end_on_the_reference_and_target_exactly():
    frames, t = _turning_frames()
    noisy = frames.copy()
    noisy[0] += 1e-13  # the interpolation's round-off at the ends
    noisy[-1] -= 1e-13
    back = stored_frames(noisy, t, frames[0], frames[-1])
    assert back.dtype == np.float64 and back.shape == frames.shape
    assert np.array_equal(back[0], frames[0]) and np.array_equal(back[-1], frames[-1])
    inner = t[1:-1, None, None]
    offsets = np.abs(frames[1:-1] - ((1.0 - inner) * frames[0] + inner * frames[-1]))
    err = np.abs(back[1:-1] - frames[1:-1]).max()
    assert 0.0 < err <= 2.0 ** -23 * offsets.max()  # float32 rounding of the offsets
    assert err <= 1e-7 * bbox_diagonal(frames[0])


def test_read_keyframes_gives_the_stored_frames_and_other_datasets_as_read_artifact(tmp_path):
    frames, t = _turning_frames(5)
    faces = icosphere(2)[1]
    write_artifact(tmp_path / "k.h5", "keyframes",
                   {"t": t, "frame_offsets": frame_offsets(frames, t, frames[0], frames[-1]), "faces": faces,
                    "reference": frames[0], "target": frames[-1]}, params={}, inputs=[], timings={})
    data, attrs = read_keyframes(tmp_path / "k.h5", ["faces", "frames"])
    assert set(data) == {"faces", "frames"} and attrs["stage"] == "keyframes"
    assert np.array_equal(data["frames"], stored_frames(frames, t, frames[0], frames[-1]))
    assert np.array_equal(data["faces"], faces)
    with h5py.File(tmp_path / "k.h5", "r") as fh:
        assert fh["frame_offsets"].dtype == np.float32 and "frames" not in fh
