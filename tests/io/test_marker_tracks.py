"""Marker tracks: CSV (any row order) and NPZ read the same; bad files are named with the problem."""

import numpy as np
import pytest

from posefix.io.errors import InputError
from posefix.io.marker_tracks import MarkerTracks, read_tracks, write_tracks_csv


def tracks_of(markers, count=4):
    frames = np.arange(10, 10 + count)
    return MarkerTracks(frames, np.array([f"m{i}" for i in range(len(markers))]),
                        np.stack([markers + [0.05 * k, 0.0, 0.02 * k] for k in range(count)]))


def test_csv_and_npz_of_the_same_tracks_read_the_same(tmp_path):
    tracks = tracks_of(np.random.default_rng(0).uniform(-1.0, 1.0, (6, 3)))
    write_tracks_csv(tmp_path / "t.csv", tracks)
    lines = (tmp_path / "t.csv").read_text().splitlines()
    (tmp_path / "shuffled.csv").write_text("\n".join([lines[0]] + lines[1:][::-1]) + "\n")  # any row order
    np.savez(tmp_path / "t.npz", tracks=tracks.positions, markers=tracks.markers, frames=tracks.frames)
    for path in ("t.csv", "shuffled.csv", "t.npz"):
        read = read_tracks(tmp_path / path)
        assert np.array_equal(read.positions, tracks.positions), path
        assert read.frames.tolist() == tracks.frames.tolist() and read.markers.tolist() == tracks.markers.tolist()


@pytest.mark.parametrize("text, problem", [
    ("frame,marker,x\n0,a,1\n", "header must be frame,marker,x,y,z"),
    ("frame,marker,x,y,z\n0,a,0,0,0\n0,b,0,0,0\n1,a,0,0,0\n", "marker b appears 0 times in frame 1"),
    ("frame,marker,x,y,z\n0,a,0,0,zero\n", "line 2: frame must be an integer and x, y, z numbers"),
    ("frame,marker,x,y,z\n0,a,0,0,nan\n", "marker a has no finite position in frame 0"),
])
def test_bad_tracks_are_named_with_the_problem(tmp_path, text, problem):
    (tmp_path / "bad.csv").write_text(text)
    with pytest.raises(InputError, match="bad.csv: " + problem):
        read_tracks(tmp_path / "bad.csv")
