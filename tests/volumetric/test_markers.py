"""S4's marker animation: markers at rest leave the mesh at rest, a rigid motion of the markers moves the
mesh rigidly, the stage writes the same library from CSV and NPZ tracks and names a marker far off."""

import numpy as np
import pytest

from conftest import ROOT, run_stage
from posefix.mesh.rotations import rotation_exp
from posefix.io.marker_tracks import MarkerTracks, read_tracks, write_tracks_csv
from posefix.io.meshes import read_mesh, write_mesh
from posefix.volumetric.markers import MarkerAnimator
from posefix.volumetric.shapes import tet_grid
from posefix.volumetric.transfer import boundary_faces


@pytest.fixture(scope="module")
def bar():
    """A 3 x 1 x 1 bar: its tet grid, its boundary surface and 6 markers on the surface."""
    X, T = tet_grid((6, 2, 2), (3.0, 1.0, 1.0))
    used = np.unique(boundary_faces(T)[0])
    V = X[used]
    ids = [int(np.argmin(np.linalg.norm(V - p, axis=1))) for p in
           ([0, 0, 0], [0, 1, 1], [1.5, 1, 0], [1.5, 0, 1], [3, 0, 1], [3, 1, 0])]
    return V, X, T, V[ids]


def test_markers_at_rest_leave_the_mesh_at_rest(bar):
    V, X, T, markers = bar
    result = MarkerAnimator(V, X, T, markers).animate(np.repeat(markers[None], 3, axis=0))
    assert np.abs(result.frames - V).max() <= 1e-12 * 3.3 and result.residuals.max() <= 1e-12
    assert result.shear.max() <= 1e-12


def test_rigidly_moved_markers_move_the_mesh_rigidly(bar):
    V, X, T, markers = bar
    turns = [rotation_exp(np.array([[0.0, 0.0, a]]))[0] for a in np.linspace(0.0, 1.2, 7)]
    tracks = np.stack([markers @ R.T + [0.1 * k, 0.0, 0.0] for k, R in enumerate(turns)])
    result = MarkerAnimator(V, X, T, markers).animate(tracks, iterations=100, first_iterations=100)
    expected = np.stack([V @ R.T + [0.1 * k, 0.0, 0.0] for k, R in enumerate(turns)])
    assert np.abs(result.frames - expected).max() <= 1e-6 and result.residuals.max() <= 1e-6
    errors = [np.abs(MarkerAnimator(V, X, T, markers).animate(tracks, it, it).frames - expected).max()
              for it in (0, 3, 10)]  # six markers pin a turn slowly: 0.24 after 3 iterations a frame, 0.038 after 10
    assert errors[0] > errors[1] > errors[2] > 1e-2


def test_the_stage_writes_the_same_library_from_csv_and_npz(tmp_path, demo):
    ref = tmp_path / "demo-reference.obj"
    write_mesh(ref, demo[0], demo[1])  # the demo limb the tracks were made on
    tracks = read_tracks(ROOT / "examples" / "demo-limb-markers.csv")
    np.savez(tmp_path / "demo.npz", tracks=tracks.positions, markers=tracks.markers, frames=tracks.frames)
    for source, name in ((ROOT / "examples" / "demo-limb-markers.csv", "csv"), (tmp_path / "demo.npz", "npz")):
        run_stage("volumetric_animate", "--mesh", ref, "--tracks", source, "--out", tmp_path / name, "--name", "m",
                  "--artifact", tmp_path / f"{name}.h5", "--tet-vertices", 300)
    V, F = read_mesh(ref)
    names = sorted(p.name for p in (tmp_path / "csv").iterdir())
    assert names == ["m-0000.obj", "m-0001.obj"] + [f"m-{k:04d}.obj" for k in range(2, 13)] + ["m-reference.obj"]
    for name in names:
        a, b = (tmp_path / "csv" / name).read_bytes(), (tmp_path / "npz" / name).read_bytes()
        assert a == b, name
    first, F0 = read_mesh(tmp_path / "csv" / "m-0000.obj")
    assert np.array_equal(F0, F) and np.abs(first - V).max() <= 1e-5  # the first frame is the rest pose
    far = tmp_path / "far.csv"
    write_tracks_csv(far, MarkerTracks(tracks.frames, tracks.markers, tracks.positions + [0.0, 2.0, 0.0]))
    proc = run_stage("volumetric_animate", "--mesh", ref, "--tracks", far, "--out", tmp_path / "far",
                     "--artifact", tmp_path / "far.h5", check=False)
    assert proc.returncode == 2 and "marker m0 is" in proc.stderr and "first frame must be the rest pose" in proc.stderr
    assert not (tmp_path / "far.h5").exists() and not (tmp_path / "far").exists()
