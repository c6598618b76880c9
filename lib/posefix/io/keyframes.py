"""Key frames on disk: ``keyframes.h5`` stores the inner frames as float32 offsets from the linear blend
``(1 - t) V_ref + t V_tgt`` of the reference and the target, which it stores exactly (float64).

The offsets are at most a few tenths of the bounding-box diagonal ``d`` (a limb turning away from the straight path),
so float32 keeps them to about 1e-8 d (kids-0001: 3.3e-9 d, lion-04: 6.7e-9 d), and they take a third of the
frames' disk in float64 (kids-0001's 11 frames of 59.7k vertices, gzip: 13.1 MB -> 4.4 MB). The first and last
frames are the reference and the target themselves. The key frames in memory are the ones read back
(:func:`stored_frames`), so a pose repaired in memory and one repaired by the pipeline see the same frames.
"""

import numpy as np

from posefix.io.artifacts import read_artifact


def _blend(t, V_ref, V_tgt):
    """``(1 - t) V_ref + t V_tgt`` at the inner times ``t[1:-1]``, (K - 2, n, 3) float64."""
    inner = np.asarray(t, dtype=np.float64)[1:-1, None, None]
    return (1.0 - inner) * V_ref + inner * V_tgt


def frame_offsets(frames, t, V_ref, V_tgt):
    """The inner key frames as offsets from the linear blend of ``V_ref`` and ``V_tgt``.

    Parameters
    ----------
    frames : (K, n, 3) float64
        Key frames at the times ``t`` (K,), in units of length.
    t : (K,) float64
        Times in [0, 1], ``t[0] = 0`` and ``t[-1] = 1``.
    V_ref, V_tgt : (n, 3) float64

    Returns
    -------
    (K - 2, n, 3) float32
        ``frames[1:-1] - ((1 - t) V_ref + t V_tgt)``, rounded to float32.

    Examples
    --------
    >>> import numpy as np
    >>> V_ref, V_tgt = np.zeros((1, 3)), np.ones((1, 3))
    >>> frame_offsets(np.array([[[0, 0, 0]], [[0.5, 0.5, 0.75]], [[1, 1, 1]]]), [0, 0.5, 1], V_ref, V_tgt)[0, 0]
    array([0.  , 0.  , 0.25], dtype=float32)
    """
    return (np.asarray(frames)[1:-1] - _blend(t, V_ref, V_tgt)).astype(np.float32)


def frames_from_offsets(offsets, t, V_ref, V_tgt):
    """The key frames from their :func:`frame_offsets`: ``V_ref``, the blend plus the offsets, ``V_tgt``.

    Parameters
    ----------
    offsets : (K - 2, n, 3) float32
    t : (K,) float64
    V_ref, V_tgt : (n, 3) float64

    Returns
    -------
    (K, n, 3) float64
    """
    V_ref, V_tgt = np.asarray(V_ref, dtype=np.float64), np.asarray(V_tgt, dtype=np.float64)
    inner = _blend(t, V_ref, V_tgt) + np.asarray(offsets, dtype=np.float32).astype(np.float64)
    return np.concatenate([V_ref[None], inner, V_tgt[None]])


def stored_frames(frames, t, V_ref, V_tgt):
    """The key frames as ``keyframes.h5`` gives them back, (K, n, 3) float64: the endpoints ``V_ref`` and ``V_tgt``,
    the inner frames to float32 precision of their offsets from the linear blend."""
    return frames_from_offsets(frame_offsets(frames, t, V_ref, V_tgt), t, V_ref, V_tgt)


def read_keyframes(path, names):
    """:func:`posefix.io.artifacts.read_artifact` of a ``keyframes`` artifact, where the name ``"frames"`` gives the
    key frames (K, n, 3) float64 (:func:`frames_from_offsets` of the stored ``frame_offsets``)."""
    stored = [n for n in names if n != "frames"]
    if "frames" in names:
        stored += [n for n in ("frame_offsets", "t", "reference", "target") if n not in stored]
    data, attrs = read_artifact(path, "keyframes", stored)
    if "frames" in names:
        data["frames"] = frames_from_offsets(data["frame_offsets"], data["t"], data["reference"], data["target"])
    return {n: data[n] for n in names}, attrs
