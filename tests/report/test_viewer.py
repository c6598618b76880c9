"""The 3D viewer page (posefix.report.viewer, stage viewer): its encoding round trip, and the page itself in headless
Chromium (skipped without it; `make system` installs Debian's chromium as root)."""

import base64
import html
import json
import re
import shutil
import subprocess

import numpy as np
import pytest
from matplotlib.image import imread

from conftest import icosphere, run_stage
from posefix.io.artifacts import read_artifact, read_repair, write_artifact
from posefix.mesh.intersections import self_intersecting_pairs
from posefix.report.viewer import decode_array, decode_positions, encode_array, encode_positions
from posefix.verify.flags import REPLACED_PASS_THROUGH

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
needs_chromium = pytest.mark.skipif(CHROMIUM is None, reason="needs headless Chromium on PATH (Debian: apt-get "
                                    "install chromium; `make system` installs it as root)")


@pytest.mark.parametrize("dtype", ["<f4", "<u4", "<i4", "<f8", "u1"])
def test_an_array_survives_its_encoding_bit_for_bit(dtype):
    a = (np.random.default_rng(0).normal(size=(37, 3)) * 1000).astype(dtype)
    assert np.array_equal(decode_array(encode_array(a), dtype, a.shape), a)
    assert decode_array(encode_array(np.zeros(0, dtype)), dtype, (0,)).shape == (0,)


def test_positions_decode_to_their_float32_values_with_or_without_a_base():
    V, _ = icosphere(3)
    X = V.copy()
    X[:10] += 0.01  # a repair that moved a few vertices
    assert np.array_equal(decode_positions(encode_positions(V), len(V)), V.astype(np.float32))
    assert np.array_equal(decode_positions(encode_positions(X, V), len(X), V), X.astype(np.float32))
    assert len(encode_positions(X, V)) < len(encode_positions(X)) / 5  # the unchanged vertices cost next to nothing


def test_a_60k_vertex_repair_that_moved_every_vertex_stays_under_3_mb():
    rng = np.random.default_rng(1)
    target = rng.normal(size=(60_000, 3))
    record = encode_positions(target + rng.normal(scale=1e-3, size=target.shape), target)
    assert len(record) < 3e6 and len(encode_array(np.packbits(rng.random(120_000) < 0.1))) < 3e4


def test_the_encoding_is_deterministic():
    V, _ = icosphere(2)
    assert encode_positions(V * 1.1, V) == encode_positions(V * 1.1, V)


def _three_spheres(b_centre):
    """Spheres A, B and a small C overlapping A (the reference's own intersection); B at ``b_centre``: (V, F)."""
    parts = [icosphere(2, 1.0, (-1.5, 0, 0)), icosphere(2, 1.0, b_centre), icosphere(1, 0.4, (-0.6, 0, 0))]
    offsets = np.cumsum([0] + [len(V) for V, _ in parts[:-1]])
    return np.vstack([V for V, _ in parts]), np.vstack([F + o for (_, F), o in zip(parts, offsets)])


def _entry(pose, repairs):
    faces = {"target": 1, "keyframes_max": 1, "repaired": 0, "repaired_new": 0, "repaired_new_in_fallback": 0}
    return {"pose": pose, "intersecting_faces": faces, "deviation": {"constrained_max": 0.0}, "fallback_vertices": 0,
            "repairs": {name: {} for name in repairs}, "status": {"kind": "ok", "reason": ""}}


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    """Artifacts of a two-pose synthetic library (every file the stage reads), and the page the stage writes."""
    tmp = tmp_path_factory.mktemp("viewer")
    V_ref, F = _three_spheres((1.5, 0, 0))
    d = float(np.linalg.norm(np.ptp(V_ref, axis=0)))
    common = {"params": {}, "inputs": [], "timings": {}}
    for i, pose in enumerate(["p-01", "p-02"]):
        V_tgt = _three_spheres((0.3 + 0.1 * i, 0, 0))[0]  # B inside A: new intersections
        repaired = _three_spheres((1.0, 0, 0))[0]  # B apart again
        frames = [self_intersecting_pairs(V, F) for V in (V_ref, V_tgt)]
        mask = np.arange(len(V_ref)) % 3 > 0
        replaced = np.where(np.arange(len(V_ref)) < 40, REPLACED_PASS_THROUGH, 0).astype(np.uint8)
        folder = tmp / "results" / pose
        write_artifact(folder / "keyframes.h5", "keyframes", {"reference": V_ref, "target": V_tgt, "faces": F},
                       metrics={"bbox_diagonal": d}, **common)
        write_artifact(folder / "classify.h5", "classify", {"mask": mask, "pairs": np.vstack(frames),
                                                            "pair_offsets": np.cumsum([0, *map(len, frames)])},
                       **common)
        write_artifact(folder / "verify.h5", "verify", {
            "repaired": repaired, "deviation": np.linalg.norm(repaired - V_tgt, axis=1) / d, "replaced": replaced,
            "pairs": self_intersecting_pairs(repaired, F)}, **common)
        medial = V_tgt + 0.01 * (i + 1)
        medial[:len(medial) // 3, 2] *= 0.05  # sphere A flattened: faces crushed beyond the distortion limit
        write_artifact(folder / "medial.h5", "repair_medial", {"repaired": medial}, **common)
    summary = tmp / "summary.json"
    summary.write_text(json.dumps({"library": "spheres", "poses": [_entry(p, ["medial"]) for p in ["p-01", "p-02"]]}))
    run_stage("viewer", "--summary", summary, "--results", tmp / "results", "--out", tmp / "viewer.html")
    return tmp


def test_the_stage_writes_the_same_page_for_the_same_inputs(library, tmp_path):
    run_stage("viewer", "--summary", library / "summary.json", "--results", library / "results",
              "--out", tmp_path / "viewer.html")
    page = (library / "viewer.html").read_bytes()
    assert (tmp_path / "viewer.html").read_bytes() == page
    assert b"<script src=" not in page and b"<link" not in page  # everything inline


def test_the_stage_names_a_file_that_is_no_summary(library, tmp_path):
    (tmp_path / "summary.json").write_text("[1, 2]")
    proc = run_stage("viewer", "--summary", tmp_path / "summary.json", "--results", library / "results",
                     "--out", tmp_path / "viewer.html", check=False)
    assert proc.returncode != 0 and "not a posefix summary.json" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and not (tmp_path / "viewer.html").exists()


def browse(page, state, *action, tmp):
    """Open ``page`` at ``#state`` in headless Chromium with ``action`` (--dump-dom, --screenshot=PNG); fails on
    any console message. Returns stdout."""
    proc = subprocess.run([CHROMIUM, "--headless=new", "--no-sandbox", "--use-angle=swiftshader",
                           "--enable-unsafe-swiftshader", "--disable-dev-shm-usage", "--window-size=900,600",
                           "--virtual-time-budget=20000",
                           "--enable-logging=stderr", "--v=0", f"--user-data-dir={tmp / 'profile'}", *action,
                           f"{page.as_uri()}#{state}"], capture_output=True, text=True, timeout=180)
    assert proc.returncode == 0, proc.stderr[-2000:]
    console = [line for line in proc.stderr.splitlines() if ":CONSOLE" in line]
    assert not console, console
    return proc.stdout


def dump(page, state, tmp):
    """The page's status and its ``dump`` (decoded positions and drawn corners, float32) at ``#state``."""
    dom = browse(page, state, "--dump-dom", tmp=tmp)
    status = re.search(r'<body[^>]*data-status="([^"]*)"', dom).group(1)
    text = html.unescape(re.search(r'<pre id="dump">(.*?)</pre>', dom, re.S).group(1))
    return status, (json.loads(text) if text else None)


def screenshot(page, state, tmp):
    """RGB of the page at ``#state`` (900 x 600 window), (h, w, 3) float in [0, 1]."""
    path = tmp / f"{abs(hash(state))}.png"
    browse(page, state, f"--screenshot={path}", tmp=tmp)
    return imread(path)[..., :3]


def _floats(text, shape):
    return np.frombuffer(base64.b64decode(text), "<f4").reshape(shape)


@needs_chromium
@pytest.mark.parametrize("mesh, pose", [("target", "p-02"), ("space-time", "p-01"), ("medial", "p-02"),
                                        ("reference", "p-01")])
def test_the_page_shows_each_mesh_with_its_own_vertex_order_and_faces(library, tmp_path, mesh, pose):
    status, shown = dump(library / "viewer.html", f"pose={pose}&mesh={mesh}&dump={mesh}", tmp_path)
    assert status == "ready" and shown["mesh"] == mesh
    kf, _ = read_artifact(library / "results" / pose / "keyframes.h5", "keyframes", ["reference", "target", "faces"])
    files = {"target": kf["target"], "reference": kf["reference"],
             "space-time": read_artifact(library / "results" / pose / "verify.h5", "verify", ["repaired"])[0]["repaired"],
             "medial": read_repair(library / "results" / pose / "medial.h5", "medial", ["repaired"])[0]["repaired"]}
    X, F = files[mesh], kf["faces"]
    assert np.array_equal(_floats(shown["positions"], X.shape), X.astype(np.float32))
    assert np.array_equal(_floats(shown["corners"], (len(F), 3, 3)), X.astype(np.float32)[F])


def _red(rgb):
    """Pixels of the new intersections' red (shaded), (h, w) bool."""
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    return (r > 0.35) & (g < 0.45 * r) & (b < 0.45 * r)


@needs_chromium
def test_the_page_draws_and_switching_to_the_repair_changes_the_intersections_pixels(library, tmp_path):
    page = library / "viewer.html"
    target = screenshot(page, "pose=p-01&mesh=target", tmp_path)
    repaired = screenshot(page, "pose=p-01&mesh=space-time", tmp_path)
    view = target[120:, 300:]  # right of the pose list, below the buttons
    assert (view.sum(axis=2) < 2.9).mean() > 0.02 and len(np.unique(view.reshape(-1, 3), axis=0)) > 50  # not blank
    red = _red(target)
    red[540:] = False  # the legend's swatch
    assert red.sum() > 200, red.sum()
    changed = np.abs(target - repaired).sum(axis=2) > 0.1
    assert changed[red].mean() > 0.8  # where the target's new intersections were
    assert _red(repaired).sum() < red.sum() / 5


@needs_chromium
def test_the_heat_map_toggle_changes_the_colours(library, tmp_path):
    page = library / "viewer.html"
    faces = screenshot(page, "pose=p-01&mesh=space-time", tmp_path)
    heat = screenshot(page, "pose=p-01&mesh=space-time&mode=heat", tmp_path)
    assert (np.abs(faces - heat).sum(axis=2) > 0.1).mean() > 0.02


@needs_chromium
def test_the_distortion_toggle_colours_the_crushed_faces_and_names_the_limit(library, tmp_path):
    page = library / "viewer.html"
    faces = screenshot(page, "pose=p-01&mesh=medial", tmp_path)
    crushed = screenshot(page, "pose=p-01&mesh=medial&mode=distortion", tmp_path)
    repaired = screenshot(page, "pose=p-01&mesh=space-time&mode=distortion", tmp_path)
    purple = [(np.abs(rgb - [0.55, 0.20, 0.80]).max(axis=2) < 0.25)[120:540] for rgb in (faces, crushed, repaired)]
    assert purple[1].sum() > 500 and purple[0].sum() < purple[1].sum() / 10  # the flattened sphere, shaded
    assert purple[2].sum() < purple[1].sum() / 10  # the space-time repair moved B rigidly: nothing distorted
    dom = browse(page, "pose=p-01&mesh=medial&mode=distortion", "--dump-dom", tmp=tmp_path)
    assert "beyond 4x" in dom and "distorted" in dom


def test_the_page_records_each_repairs_distorted_faces(library):
    text = (library / "viewer.html").read_text()
    data = json.loads(re.search(r'<script type="application/json" id="posefix-data">(.*?)</script>', text,
                                re.S).group(1).replace("<\\/", "</"))
    counts = {m["name"]: m["distorted_count"] for m in data["poses"][0]["meshes"]}
    assert counts["medial"] > 50 and counts["space-time"] == 0 and data["distortion_limit"] == 4.0


@needs_chromium
def test_side_by_side_and_regions_load_without_error(library, tmp_path):
    status, _ = dump(library / "viewer.html", "pose=p-02&mesh=medial&left=target&mode=regions", tmp_path)
    assert status == "ready"
