"""Pose libraries: discovery, validation, and one clear error per kind of bad input.

Every bad input is checked through the stage command line: exit code 2, a single line on stderr
naming the file and the problem, and no output file left behind.
"""

import gzip
import shutil
from pathlib import Path

import numpy as np
import pytest

from conftest import icosphere, run_stage, shared_library
from posefix.io.errors import InputError
from posefix.io.library import MIN_REFERENCE_VERTICES, discover_library, read_vertex_ids
from posefix.io.meshes import write_mesh
from posefix.spacetime.rbf import POLY_TERMS


@pytest.fixture
def library(tmp_path):
    """A clean three-pose library of spheres: sphere-reference.obj, a.obj, b.off."""
    V, F = icosphere(1)
    folder = tmp_path / "lib"
    write_mesh(folder / "sphere-reference.obj", V, F)
    write_mesh(folder / "a.obj", V * 1.1, F)
    write_mesh(folder / "b.off", V + 0.1, F)
    return folder, V, F


def _expect_error(tmp_path, folder, *needles, extra=()):
    out = tmp_path / "out" / "library.h5"
    proc = run_stage("validate", "--library", folder, "--out", out, *extra, check=False)
    assert proc.returncode == 2, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if "error:" in line]
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert lines[0].startswith("posefix validate: error: ")
    for needle in needles:
        assert needle in lines[0], lines[0]
    assert not out.parent.exists() or not any(out.parent.iterdir())  # no partial output
    return lines[0]


def test_discovery_of_the_lion_library():
    lib = discover_library(shared_library("lion-poses"))
    assert lib.name == "lion-poses" and lib.reference.name == "lion-reference"
    assert [p.name for p in lib.poses] == [f"lion-{i:02d}" for i in range(1, 10)]


def test_discovery_with_explicit_reference_and_subset(library):
    folder, _, _ = library
    lib = discover_library(folder, reference="a.obj", poses=["b"])
    assert lib.reference.name == "a" and [p.name for p in lib.poses] == ["b"]


def test_hidden_files_and_os_metadata_are_not_read(tmp_path, library):
    folder, _, _ = library
    (folder / "._a.obj").write_bytes(b"\x00\x05\x16\x07AppleDouble")  # macOS metadata beside a.obj
    (folder / ".b-backup.obj").write_text("garbage")
    (folder / "__MACOSX").mkdir()
    (folder / "__MACOSX" / "._sphere-reference.obj").write_bytes(b"\x00\x05")
    lib = discover_library(folder)
    assert [p.name for p in lib.poses] == ["a", "b"] and lib.reference.name == "sphere-reference"
    run_stage("validate", "--library", folder, "--out", tmp_path / "library.h5")


def test_a_library_too_small_for_the_fit_stops_in_validate(tmp_path):
    folder = tmp_path / "tiny"
    V, F = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2]])
    write_mesh(folder / "tri-reference.obj", V, F)
    write_mesh(folder / "tri-01.obj", V * 2.0, F)
    _expect_error(tmp_path, folder, "tri-reference.obj", "reference has 3 vertices", "at least 15")


def test_valid_library_passes(tmp_path, library):
    folder, _, _ = library
    run_stage("validate", "--library", folder, "--out", tmp_path / "library.h5")
    assert (tmp_path / "library.h5").exists()


def test_nan_coordinates(tmp_path, library):
    folder, V, F = library
    bad = V.copy()
    bad[5, 1] = np.nan
    write_mesh(folder / "a.obj", bad, F)
    _expect_error(tmp_path, folder, "a.obj", "NaN or infinite", "vertex 5")


def test_a_vertex_far_outside_the_reference_is_one_line_naming_it(tmp_path, library):
    folder, V, F = library
    far = V + 50.0 * np.ptp(V, axis=0)  # a pose may move far (50 diagonals here) ...
    write_mesh(folder / "a.obj", far, F)
    run_stage("validate", "--library", folder, "--out", tmp_path / "ok.h5")
    far[7] = [1e30, 0.0, 0.0]  # ... but not a vertex at 1e30 (a typo, a unit mismatch)
    write_mesh(folder / "a.obj", far, F)
    _expect_error(tmp_path, folder, "a.obj", "vertex 7 [1e+30, ", "bounding-box diagonals of the reference")


def test_infinite_coordinates(tmp_path, library):
    folder, V, F = library
    bad = V.copy()
    bad[3, 0] = np.inf
    write_mesh(folder / "b.off", bad, F)
    _expect_error(tmp_path, folder, "b.off", "NaN or infinite")


BAD_FILES = [  # file name, bytes, what the one error line must say
    ("a.obj", b"", "empty file"),
    ("c.ply", b"\x00\x01garbage that is no ply" * 10, "cannot be read as PLY"),
    ("c.obj.gz", gzip.compress(b"v 0 0 0\n")[:-6], "gzip"),
    ("c.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 99999\n", "out of range"),
    ("c.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 0 2 4\n", "line 6: face vertex index 0"),
    ("c.obj", b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n", "only triangle meshes"),
    # each kind of broken OBJ has its own message, indices 1-based as in the file
    ("c.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 999\n", "line 4: face vertex index 999 is out of range 1..3"),
    ("c.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2", "line 6: a face with 2 vertices (truncated"),
    ("c.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nv 0.5 0", "line 5: a vertex with 2 coordinates (truncated"),
    ("c.obj", b"ply\nformat ascii 1.0\nelement vertex 3\n", "PLY data in a .obj file (wrong extension?)"),
    ("c.obj", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "OFF data in a .obj file"),
    ("c.obj", bytes(range(256)) * 8, "binary data, not an OBJ text file"),
    ("c.obj", b"hello world\nthis is no mesh\n", "no vertex lines"),
]


@pytest.mark.parametrize("name, data, problem", BAD_FILES, ids=[f"{n}: {p}" for n, _, p in BAD_FILES])
def test_a_bad_file_is_one_line_naming_it(tmp_path, library, name, data, problem):
    folder, _, _ = library
    (folder / name).write_bytes(data)
    _expect_error(tmp_path, folder, name, problem)


def test_no_reference(tmp_path, library):
    folder, _, _ = library
    (folder / "sphere-reference.obj").rename(folder / "c.obj")
    _expect_error(tmp_path, folder, str(folder), "no reference found")


def test_several_references(tmp_path, library):
    folder, _, _ = library
    shutil.copy(folder / "sphere-reference.obj", folder / "other-reference.obj")
    _expect_error(tmp_path, folder, "several reference candidates")


def test_face_index_out_of_range_in_ply(tmp_path, library):
    folder, V, F = library
    bad = F.copy()
    bad[2, 1] = len(V)
    write_mesh(folder / "c.ply", V, bad)
    _expect_error(tmp_path, folder, "c.ply", "out of range")


def test_degenerate_reference_face(tmp_path, library):
    folder, V, F = library
    bad = F.copy()
    bad[7] = [bad[7, 0], bad[7, 0], bad[7, 2]]
    write_mesh(folder / "sphere-reference.obj", V, bad)
    _expect_error(tmp_path, folder, "sphere-reference.obj", "degenerate faces", "face 7")


def test_vertices_in_no_face_are_refused_in_one_line_naming_them(tmp_path, library):
    """Before: the fit ended in "Factor is exactly singular"."""
    folder, V, F = library
    extra = np.vstack([V, [[2.0, 0, 0], [0, 2.0, 0]]])
    for name in ("sphere-reference.obj", "a.obj", "b.off"):
        write_mesh(folder / name, extra, F)
    line = _expect_error(tmp_path, folder)
    assert line == (f"posefix validate: error: {folder / 'sphere-reference.obj'}: reference has 2 vertices in no face "
                    f"({len(V)}, {len(V) + 1}): a loose vertex has no surface to move with (remove it from the "
                    "library's meshes)")


def test_zero_area_reference_face(tmp_path, library):
    folder, V, F = library
    bad = V.copy()
    a, b, c = F[4]
    bad[c] = 0.5 * (bad[a] + bad[b])  # collinear corners
    write_mesh(folder / "sphere-reference.obj", bad, F)
    _expect_error(tmp_path, folder, "sphere-reference.obj", "zero-area faces")


def test_vertex_count_mismatch(tmp_path, library):
    folder, V, F = library
    write_mesh(folder / "a.obj", np.vstack([V, [[5.0, 5.0, 5.0]]]), F)
    _expect_error(tmp_path, folder, "a.obj", f"{len(V) + 1} vertices, the reference has {len(V)}")


def test_face_array_mismatch(tmp_path, library):
    folder, V, F = library
    write_mesh(folder / "b.off", V, F[:, [1, 2, 0]])
    _expect_error(tmp_path, folder, "b.off", "face array differs from the reference")


def test_unknown_pose_in_subset(tmp_path, library):
    folder, _, _ = library
    _expect_error(tmp_path, folder, "pose(s) not found: zzz", extra=("--poses", "a,zzz"))


def test_keyframes_stage_reports_bad_target_and_keeps_old_output(tmp_path, library):
    folder, V, F = library
    out = tmp_path / "kf.h5"
    run_stage("keyframes", "--reference", folder / "sphere-reference.obj", "--target", folder / "a.obj",
              "--out", out, "--count", 3)
    before = out.read_bytes()
    write_mesh(folder / "a.obj", V[:-1], F[:10])
    proc = run_stage("keyframes", "--reference", folder / "sphere-reference.obj", "--target", folder / "a.obj",
                     "--out", out, check=False)
    errors = [line for line in proc.stderr.splitlines() if "error:" in line]
    assert proc.returncode == 2 and len(errors) == 1 and "Traceback" not in proc.stderr
    assert "a.obj" in errors[0]
    assert out.read_bytes() == before  # nothing already computed is lost or corrupted
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".kf")] == []


def test_vertex_id_files(tmp_path):
    (tmp_path / "ids.txt").write_text("# hand-picked\n1 2, 3\n10\n")
    assert read_vertex_ids(tmp_path / "ids.txt").tolist() == [1, 2, 3, 10]
    (tmp_path / "bad.txt").write_text("1 two 3\n")
    with pytest.raises(InputError, match="not a vertex id: 'two'"):
        read_vertex_ids(tmp_path / "bad.txt")


def test_files_that_cannot_be_poses_are_left_out_alone_with_their_cause(tmp_path, library):
    folder, V, F = library
    (folder / "c.obj").symlink_to(tmp_path / "nowhere.obj")  # a link to nowhere
    (folder / "d.obj").symlink_to(folder / "d.obj")  # a loop
    write_mesh(folder / "walk{2}.obj", V, F)  # Snakemake would read {2} as a wildcard
    lib = discover_library(folder)
    assert [p.name for p in lib.poses] == ["a", "b"]
    assert {Path(path).name: cause for path, cause in lib.refused} == {
        "c.obj": f"a link to {tmp_path / 'nowhere.obj'}: No such file or directory",
        "d.obj": f"a link to {folder / 'd.obj'}: Too many levels of symbolic links",
        "walk{2}.obj": "braces in the file name (Snakemake's rules read them as wildcards): rename the file"}
    run_stage("validate", "--library", folder, "--out", tmp_path / "library.h5")  # the others validate


def test_a_reference_that_cannot_be_read_stops_discovery_naming_it(tmp_path, library):
    folder, _, _ = library
    (folder / "sphere-reference.obj").unlink()
    (folder / "sphere-reference.obj").symlink_to(tmp_path / "gone.obj")
    with pytest.raises(InputError, match="sphere-reference.obj: a link to .*gone.obj: No such file or directory"):
        discover_library(folder)
    for name in ("a.obj", "b.off"):
        (folder / name).unlink()
    (folder / "a{1}.obj").write_text("")
    (folder / "sphere-reference.obj").unlink()
    write_mesh(folder / "sphere-reference.obj", *icosphere(1))
    with pytest.raises(InputError, match=r"no target poses besides the reference; a\{1\}.obj: braces"):
        discover_library(folder)


def test_unicode_file_names(tmp_path, library):
    folder, V, F = library
    write_mesh(folder / "pöse-ü.obj", V * 0.9, F)
    run_stage("validate", "--library", folder, "--out", tmp_path / "library.h5")
    import h5py
    with h5py.File(tmp_path / "library.h5", "r") as fh:
        assert "pöse-ü" in [n.decode() for n in fh["poses/name"][()]]


def test_unwritable_output_is_one_line(tmp_path, library):
    folder, _, _ = library
    (tmp_path / "afile").write_text("")
    proc = run_stage("validate", "--library", folder, "--out", tmp_path / "afile" / "x.h5", check=False)
    errors = [line for line in proc.stderr.splitlines() if "error:" in line]
    assert proc.returncode == 1 and len(errors) == 1 and "Traceback" not in proc.stderr


def test_the_smallest_reference_is_the_space_time_polynomials_terms():
    assert MIN_REFERENCE_VERTICES == POLY_TERMS


def test_a_reference_that_intersects_itself_is_allowed_and_said_with_its_count(tmp_path):
    V, F = icosphere(1)
    V2, F2 = np.vstack([V, V + [0.5, 0.0, 0.0]]), np.vstack([F, F + len(V)])  # two overlapping balls
    folder = tmp_path / "lib"
    write_mesh(folder / "balls-reference.obj", V2, F2)
    write_mesh(folder / "a.obj", V2 * 1.1, F2)
    proc = run_stage("validate", "--library", folder, "--reference-only", "--out", tmp_path / "reference.h5")
    warnings = [line.split(" ", 1)[1] for line in proc.stderr.splitlines() if ": warning: " in line]
    import h5py
    with h5py.File(tmp_path / "reference.h5", "r") as fh:
        faces = int(fh["metrics"].attrs["reference_intersecting_faces"])
    assert 0 < faces < len(F2) and warnings == [
        f"posefix validate: warning: {folder / 'balls-reference.obj'}: the reference has {faces} intersecting faces: "
        "allowed (the repairs tolerate them and form no new intersection)"]
