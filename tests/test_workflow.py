"""The Snakemake workflow end to end: demo library, determinism, bad libraries (the lion poses: test_lion_library;
authored libraries: test_authoring_workflow)."""

import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from conftest import icosphere, snakemake
from posefix.workflow.demo import POSES, demo_library
from posefix.io.meshes import write_mesh

pytestmark = pytest.mark.pipeline


SUMMARY = "reports/lib/summary.json"
"""The target of the runs on library ``lib`` that need no figures and no viewer: its summary (and what it reads, the
repaired meshes among them)."""


def test_demo_run_produces_every_artifact(demo_run):
    results = demo_run / "results" / "demo"
    assert (results / "reference.h5").exists()
    for pose in POSES:
        for stage in ("validate", "keyframes", "classify", "constraints", "fit", "integrate", "verify", "downstream"):
            # constraints.h5 and integrate.h5 are intermediates: removed once fit and verify have read them (config
            # keep_intermediates: false)
            assert (results / pose.name / f"{stage}.h5").exists() == (stage not in ("constraints", "integrate"))
            assert (results / "benchmarks" / pose.name / f"{stage}.tsv").exists()
            assert (results / "logs" / pose.name / f"{stage}.log").read_text().strip()
        with h5py.File(results / pose.name / "classify.h5", "r") as fh:
            counts = fh["intersecting_faces"][()]
            assert counts[0] == 0 and counts[-1] > 0  # clean reference, intersecting target
            assert 0 < fh["mask"][()].sum() < len(fh["mask"])
        with h5py.File(results / pose.name / "fit.h5", "r") as fh:  # within budget, reason recorded
            assert fh["metrics"].attrs["stop_reason"] in ("eps", "rms", "max_centers")
            assert fh["metrics"].attrs["centers"] <= 4000


def test_demo_poses_are_repaired(demo_run):
    """S0's promise on the demo library: no new intersection, untouched regions reproduced."""
    from posefix.io.meshes import read_mesh
    summary = json.loads((demo_run / "reports" / "demo" / "summary.json").read_text())
    assert [e["pose"] for e in summary["poses"]] == [p.name for p in POSES]
    for e in summary["poses"]:
        assert e["intersecting_faces"]["target"] > 0 and e["intersecting_faces"]["repaired_new"] == 0
        assert e["deviation"]["constrained_mean"] <= 1e-3 and e["deviation"]["constrained_max"] <= 5e-3
        assert e["integrated_deviation"]["constrained_mean"] <= 1e-3  # before the snap to the target
        assert e["integrate"]["steps_max"] > 0 and e["seconds_total"] > 0
        # the downstream check ran with the session's one setting, towards both examples
        down = e["downstream"]
        assert down["k_bend"] == [0.01] and list(down["alphas"]) == ["1"]
        for example in ("original", "repaired"):
            run = down["alphas"]["1"][example]
            assert len(run["iterations"]) == 1 and run["iterations"][0] >= 1
            assert run["converged"][0] == (run["reason"][0] == "converged")
    # the point of the repair (S0 §5): Gauss-Newton converges towards more repaired demo poses than originals.
    # With one setting it is fragile: on demo-04 the contact finish's pose and one 1e-3 d away (the Newton
    # tolerance) split between converged and a collapsed triangle, as do the snap finish and the integrated pose
    # with V_C blended in; towards the originals it collapsed a triangle on 3 of the 4 when this was written.
    converged = {example: sum(e["downstream"]["alphas"]["1"][example]["converged"][0] for e in summary["poses"])
                 for example in ("original", "repaired")}
    assert converged["repaired"] >= 3 and converged["repaired"] > converged["original"], converged
    lib = demo_run / "data" / "demo"
    for pose in POSES:
        V_tgt, F = read_mesh(lib / f"{pose.name}{pose.suffix}")
        V, F2 = read_mesh(demo_run / "results" / "demo" / "repaired" / f"{pose.name}{pose.suffix}")
        assert np.array_equal(F, F2) and V.shape == V_tgt.shape
    markdown = (demo_run / "reports" / "demo" / "summary.md").read_text()
    # the repair table, the downstream table and S0 vs the other repairs (config repairs)
    assert markdown.count("| demo-") == 3 * len(POSES) and "## Space-time vs the other repairs" in markdown


@pytest.mark.parametrize("name", ["medial", "volumetric", "contact"])
def test_the_report_compares_s0_with_the_other_repairs(demo_run, name):
    """summary.json's repairs.<name>: the artifact's numbers and its deviation over S0's V_C, measured as
    S0's; renders.png has a panel per other repair."""
    from matplotlib.image import imread
    from posefix.workflow.timings import benchmark_seconds
    from posefix.verify.deviation import deviation
    summary = json.loads((demo_run / "reports" / "demo" / "summary.json").read_text())
    for e in summary["poses"]:
        folder = demo_run / "results" / "demo" / e["pose"]
        compared = e["repairs"][name]
        with h5py.File(folder / f"{name}.h5", "r") as fh, h5py.File(folder / "classify.h5", "r") as cl, \
                h5py.File(folder / "keyframes.h5", "r") as kf:
            metrics = fh["metrics"].attrs
            assert compared["intersecting_faces"] == {"repaired": metrics["intersecting_faces_repaired"],
                                                      "repaired_new": metrics["intersecting_faces_repaired_new"]}
            assert compared["iterations"] == metrics["iterations"]
            # wall seconds of the stage, as S0's (the artifact's in-process seconds are less)
            wall = benchmark_seconds(demo_run / "results" / "demo" / "benchmarks" / e["pose"], f"repair_{name}")
            assert compared["seconds"] == wall >= metrics["seconds"]
            assert "start" not in fh  # measured from the target of keyframes.h5, as space-time
            _, dev = deviation(fh["repaired"][()], kf["target"][()], cl["mask"][()],
                               kf["metrics"].attrs["bbox_diagonal"])
            if name == "volumetric":  # V_C kept exactly, the free region filled
                free = fh["free"][()]
                assert np.array_equal(fh["repaired"][()][~free], kf["target"][()][~free])
                assert free[~cl["mask"][()]].all()
            if name == "contact":  # no new intersection, by construction
                assert compared["intersecting_faces"]["repaired_new"] == 0 and not fh["new_faces"][()].any()
        assert compared["deviation"] == pytest.approx(dev) and "downstream" not in compared  # downstream.repairs
        figures = demo_run / "reports" / "demo" / "figures" / e["pose"]
        renders, deviation_map = imread(figures / "renders.png"), imread(figures / "deviation.png")
        assert 2 * renders.shape[1] == 5 * deviation_map.shape[1]  # five panels of 5 inches, two of 5
    page = (demo_run / "reports" / "demo" / "summary.html").read_text()
    assert "<th>new faces space-time / medial / volumetric / contact</th>" in page


def test_other_repairs_reach_the_report_and_the_check(tmp_path):
    """config repairs adds the other repairs' artifacts to summary and render, downstream.repairs to the check;
    repairs=[] leaves them out everywhere."""
    proc = snakemake(tmp_path, "-n", "-p", "--config", "poses=demo-01", "downstream={'repairs': True}")
    assert proc.returncode == 0, proc.stderr[-2000:]
    commands = [line for line in (proc.stdout + proc.stderr).splitlines() if "stages/" in line]
    for name in ("medial", "volumetric", "contact"):
        option = f"--repair {name}=results/demo/demo-01/{name}.h5"
        for stage in ("render", "downstream"):
            assert sum(f"stages/{stage}.py" in c and option in c for c in commands) == 1, (stage, name)
    assert any("stages/summary.py" in c and "--repairs medial,volumetric,contact" in c for c in commands)
    proc = snakemake(tmp_path, "-n", "-p", "--config", "poses=demo-01", "repairs=[]")
    assert proc.returncode == 0, proc.stderr[-2000:]
    commands = [line for line in (proc.stdout + proc.stderr).splitlines() if "stages/" in line]
    assert len(commands) > 10 and not any("--repair " in c or "medial" in c or "volumetric" in c
                                          or "repair_contact" in c for c in commands)


def test_report_has_every_section_and_non_blank_figures(demo_run):
    """`snakemake --report` after a run: one self-contained HTML file with the library page (overview, summary
    table, 3D viewer) and, for every pose, its six figures (captioned PNGs that decode and are not blank)."""
    import base64
    import io
    from html.parser import HTMLParser
    from matplotlib.image import imread

    out = demo_run / "reports" / "demo" / "report.html"
    proc = snakemake(demo_run, "--report", str(out))
    assert proc.returncode == 0, proc.stderr[-3000:]

    class Scripts(HTMLParser):
        """Text of the <script id=...> elements (the report's embedded data)."""

        def __init__(self):
            super().__init__()
            self.found, self.current = {}, None

        def handle_starttag(self, tag, attrs):
            self.current = dict(attrs).get("id") if tag == "script" else None

        def handle_data(self, data):
            if self.current:
                self.found[self.current] = self.found.get(self.current, "") + data

    parser = Scripts()
    parser.feed(out.read_text())
    data = {k: json.loads(v.strip().split("=", 1)[1].strip().rstrip(";")) for k, v in parser.found.items()
            if k in ("results", "categories")}
    poses = data["categories"]["2. Poses"]
    assert sorted(poses) == [p.name for p in POSES]
    figures = ("classification", "deviation", "downstream", "fit", "renders", "timings")
    for pose in POSES:
        assert sorted(f.rsplit("/", 1)[1] for f in poses[pose.name]) == [f"{f}.png" for f in figures]
    library = [f for files in data["categories"]["1. Library"].values() for f in files]
    assert sorted(f.rsplit("/", 1)[1] for f in library) == ["overview.png", "summary.html", "viewer.html"]
    pngs = 0
    for path, item in data["results"].items():
        assert item["caption"].strip(), path
        payload = base64.b64decode(item["data_uri"].split("base64,", 1)[1])
        if item["mime_type"] == "image/png":
            pixels = imread(io.BytesIO(payload))
            assert pixels.ndim == 3 and pixels[..., :3].var() > 0, path
            pngs += 1
        elif path.endswith("viewer.html"):
            assert all(f'"name":"{p.name}"' in payload.decode() for p in POSES)
        else:
            table = payload.decode()
            assert all(f"<td>{p.name}</td>" in table for p in POSES)
    assert pngs == len(POSES) * len(figures) + 1


def test_rerun_is_a_no_op(demo_run):
    """(A new run's outputs are the same bytes: tests/workflow/test_command.py, from another folder.)"""
    proc = snakemake(demo_run, "-n")
    assert "Nothing to be done" in proc.stdout + proc.stderr


def test_missing_reference_fails_at_startup(tmp_path):
    lib = tmp_path / "noref"
    V, F = icosphere(1)
    write_mesh(lib / "a.obj", V, F)
    proc = snakemake(tmp_path, "--config", f"library={lib}")
    assert proc.returncode != 0
    assert f"posefix: error: {lib}: no reference found" in proc.stderr
    assert "Traceback" not in proc.stderr and not (tmp_path / "results").exists()


def test_results_and_reports_that_cannot_be_written_are_refused_before_any_job_in_one_line_each(tmp_path):
    """Before: reports= on an impossible path failed at 70 % of the jobs ("WorkflowError: Failed to create output
    directory"), after every repair had run."""
    (tmp_path / "a-file").write_text("")
    proc = snakemake(tmp_path, "--config", "results=/proc/posefix", "reports=a-file/reports")
    errors = [line for line in proc.stderr.splitlines() if "error" in line.lower()]
    assert proc.returncode == 1 and errors == [
        "posefix: error: config: results=/proc/posefix: /proc/posefix/demo cannot be made: /proc takes no new folder "
        "(No such file or directory)",
        f"posefix: error: config: reports=a-file/reports: a-file/reports/demo cannot be made: {tmp_path / 'a-file'} "
        "is a file"], proc.stderr
    assert not (tmp_path / "data").exists()  # no job ran (the demo library not written)


def test_an_unreadable_reference_is_refused_at_startup_in_one_line(tmp_path):
    """Before the memory check and before any job (issue 50): the reference's own one line."""
    lib = tmp_path / "lib"
    V, F = icosphere(1)
    write_mesh(lib / "ball-01.obj", V, F)
    (lib / "ball-reference.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
    proc = snakemake(tmp_path, "--config", f"library={lib}")
    assert proc.returncode != 0 and "Traceback" not in proc.stderr
    errors = [line for line in proc.stderr.splitlines() if "error" in line]
    assert errors == [f"posefix: error: {lib / 'ball-reference.obj'}: line 4: face vertex index 7 is out of range 1..3 "
                      "(OBJ indices start at 1)"], proc.stderr
    assert not (tmp_path / "results").exists()


def test_nested_config_overrides_reach_the_stages(tmp_path):
    proc = snakemake(tmp_path, "-n", "-p", "--config", "keyframes={'count': 5, 'align': 'false'}",
                     "classify={'ring': 2, 'contact': 0.01, 'exclude': {'demo-01': [3, 4]}}")
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = proc.stdout + proc.stderr
    assert "--count 5 --no-align" in out and "--ring 2 --contact 0.01" in out and "--exclude 3,4" in out
    # after the session's one-setting downstream: replaced; 1e-05 is how Snakemake passes 0.00001 on
    proc = snakemake(tmp_path, "-n", "-p", "--config", "downstream={'k_bend': [1e-05, 0.1], 'alphas': [0.5]}")
    assert proc.returncode == 0, proc.stderr[-2000:]
    out = proc.stdout + proc.stderr
    assert "--alphas 0.5 " in out and "--k-bend 1e-05,0.1 " in out and "--alphas 1.0" not in out
    proc = snakemake(tmp_path, "-n", "--config", "classify={'exclude': {'demo-9': [1]}}")
    assert proc.returncode != 0 and "classify.exclude names pose(s) not in the library: demo-9" in proc.stderr


def test_constraints_and_integrate_are_intermediates_unless_kept(tmp_path):
    proc = snakemake(tmp_path, "-n", "--config", "poses=demo-01", "repairs=[]")
    for name in ("constraints", "integrate"):
        removed = f"Would remove temporary output results/demo/demo-01/{name}.h5"
        assert proc.returncode == 0 and removed in proc.stdout + proc.stderr, proc.stderr[-2000:]
    proc = snakemake(tmp_path, "-n", "--config", "poses=demo-01", "repairs=[]", "keep_intermediates=true")
    assert proc.returncode == 0 and "results/demo/demo-01/integrate.h5" in proc.stdout + proc.stderr
    assert "Would remove temporary output" not in proc.stdout + proc.stderr


def test_files_that_cannot_be_poses_are_left_out_alone_and_the_others_repaired(tmp_path):
    """A link to nowhere, a loop of links and braces in a name: one line each, and the good pose is repaired."""
    library = tmp_path / "lib"
    V, F = icosphere(2)
    write_mesh(library / "ball-reference.obj", V, F)
    write_mesh(library / "ball-01.obj", V * [1.2, 1.0, 0.9], F)
    write_mesh(library / "walk{2}.obj", V * 1.1, F)
    (library / "gone.obj").symlink_to(tmp_path / "nowhere.obj")
    (library / "loop.obj").symlink_to(library / "loop.obj")
    proc = snakemake(tmp_path, "--config", f"library={library}", "repairs=[]")
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr[-3000:]
    warnings = [line for line in proc.stderr.splitlines() if line.startswith("posefix: warning:")]
    assert warnings == [
        f"posefix: warning: {library / 'gone.obj'}: a link to {tmp_path / 'nowhere.obj'}: No such file or directory; "
        "left out of the library",
        f"posefix: warning: {library / 'loop.obj'}: a link to {library / 'loop.obj'}: Too many levels of symbolic "
        "links; left out of the library",
        f"posefix: warning: {library / 'walk{2}.obj'}: braces in the file name (Snakemake's rules read them as "
        "wildcards): rename the file; left out of the library"]
    summary = json.loads((tmp_path / "reports" / "lib" / "summary.json").read_text())
    assert [e["pose"] for e in summary["poses"]] == ["ball-01"]
    assert (tmp_path / "results" / "lib" / "repaired" / "ball-01.obj").exists()


def test_plain_snakemake_ends_a_failed_run_with_the_posefix_error_lines(tmp_path):
    """The README's plain `snakemake`: the posefix line of a bad pose comes again after Snakemake's job log, with
    the good pose repaired (the default profile keeps going) and in the summary and the 3D viewer, the bad one
    listed apart."""
    library = tmp_path / "lib"
    V, F = icosphere(2)
    write_mesh(library / "ball-reference.obj", V, F)
    write_mesh(library / "ball-01.obj", V * [1.2, 1.0, 0.9], F)
    (library / "ball-02.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    proc = snakemake(tmp_path, "--config", f"library={library}", "repairs=[]")
    assert proc.returncode != 0
    line = (f"posefix validate: error: {library / 'ball-02.obj'}: line 4: face vertex index 9 is out of range 1..3 "
            "(OBJ indices start at 1)")
    tail = proc.stderr.splitlines()[-8:]
    assert proc.stderr.count(line) == 1 and line.replace("posefix validate: error:", "posefix: failed in validate:") \
        in tail, "\n".join(tail)
    assert (tmp_path / "results" / "lib" / "repaired" / "ball-01.obj").exists()
    summary = json.loads((tmp_path / "reports" / "lib" / "summary.json").read_text())  # of the pose that finished
    assert [e["pose"] for e in summary["poses"]] == ["ball-01"]
    assert summary["failed"] == [{"pose": "ball-02", "error": line}]
    assert "ball-02</b>: posefix validate: error: " in (tmp_path / "reports" / "lib" / "summary.html").read_text()
    assert '"name":"ball-01"' in (tmp_path / "reports" / "lib" / "viewer.html").read_text()  # the 3D viewer too
    assert "posefix: summary of the 1 poses that finished, 1 listed as failed: reports/lib/summary.html" in tail


def test_a_library_that_would_not_fit_the_runs_memory_is_refused_up_front_in_one_line(tmp_path):
    """--resources mem_mb below what the stages need for the mesh: one line naming the reference, before any job
    starts."""
    library = tmp_path / "lib"
    V, F = icosphere(2)
    write_mesh(library / "ball-reference.obj", V, F)
    write_mesh(library / "ball-01.obj", V * [1.2, 1.0, 0.9], F)
    proc = snakemake(tmp_path, "--resources", "mem_mb=100", "--config", f"library={library}", "repairs=[]")
    assert proc.returncode != 0 and "Traceback" not in proc.stderr, proc.stderr[-3000:]
    assert proc.stderr.splitlines()[-1].startswith(
        f"posefix: error: {library / 'ball-reference.obj'}: 162 vertices need about 1.0 GB in stage "), proc.stderr
    assert "more than the 0.1 GB this run may use" in proc.stderr.splitlines()[-1]
    assert not (tmp_path / "results").exists()


def test_each_rule_asks_for_the_memory_its_stage_needs_for_the_reference_size(tmp_path):
    """A dry run shows every job's mem_mb: the stage's measured line for the reference's vertex count (read from
    the mesh file before validate_reference has run); the fit's, its cache's budget, within the run's limit."""
    from posefix.workflow.memory import stage_memory_mb
    library = tmp_path / "lib"
    V, F = icosphere(6)
    write_mesh(library / "ball-reference.obj", V, F)
    write_mesh(library / "ball-01.obj", V * [1.2, 1.0, 0.9], F)
    proc = snakemake(tmp_path, "-n", "--resources", "mem_mb=100000", "--config", f"library={library}")
    assert proc.returncode == 0, proc.stderr[-3000:]
    jobs = _dry_run_resources(proc.stdout + proc.stderr)
    for rule in ("classify", "downstream", "repair_volumetric", "verify"):
        assert jobs[rule] == stage_memory_mb(rule, len(V)), (rule, jobs)
    assert jobs["downstream"] > 1000  # above the floor at 41k vertices
    assert jobs["fit"] == 10000  # its kernel cache's budget (config fit.memory_gb) and 2 GB
    proc = snakemake(tmp_path, "-n", "--resources", "mem_mb=5000", "--config", f"library={library}")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert _dry_run_resources(proc.stdout + proc.stderr) == jobs | {"fit": 5000}  # within the run's memory


def _dry_run_resources(text):
    """{rule: mem_mb} from the job blocks of a Snakemake dry run."""
    out, rule = {}, None
    for line in text.splitlines():
        line = line.strip()
        if line.startswith("rule ") or line.startswith("localrule "):
            rule = line.split()[1].rstrip(":")
        elif line.startswith("resources:") and rule:
            fields = dict(f.split("=", 1) for f in line[len("resources:"):].replace(" ", "").split(",") if "=" in f)
            if "mem_mb" in fields:
                out[rule] = int(fields["mem_mb"])
    return out


def test_a_second_subset_of_poses_adds_to_the_librarys_summary(tmp_path):
    """poses=ball-01, then poses=ball-02: the library's summary lists both, in library order, and the first pose
    is read as it was, not rerun."""
    library = tmp_path / "lib"
    V, F = icosphere(2)
    write_mesh(library / "ball-reference.obj", V, F)
    write_mesh(library / "ball-01.obj", V * [1.2, 1.0, 0.9], F)
    write_mesh(library / "ball-02.obj", V * [0.9, 1.1, 1.0], F)
    for pose in ("ball-01", "ball-02"):
        proc = snakemake(tmp_path, "--config", f"library={library}", f"poses={pose}", "repairs=[]")
        assert proc.returncode == 0, proc.stderr[-3000:]
        if pose == "ball-01":
            first = (tmp_path / "results" / "lib" / "ball-01" / "verify.h5").stat().st_mtime_ns
    summary = json.loads((tmp_path / "reports" / "lib" / "summary.json").read_text())
    assert [e["pose"] for e in summary["poses"]] == ["ball-01", "ball-02"]
    assert "ball-01" in (tmp_path / "reports" / "lib" / "summary.md").read_text()
    assert (tmp_path / "results" / "lib" / "ball-01" / "verify.h5").stat().st_mtime_ns == first


def _limb_summary(folder, scale):
    """Repair demo-03 of the demo limb at 362 vertices with every vertex times ``scale`` (S0 and the contact repair,
    one downstream step) in ``folder``, up to the summary: its summary.json's poses."""
    V, F, poses = demo_library(around=12)
    library = folder / "limb"
    write_mesh(library / "reference.obj", scale * V, F)
    write_mesh(library / "demo-03.obj", scale * poses["demo-03"], F)
    proc = snakemake(folder, "reports/limb/summary.json", "--config", f"library={library}", "repairs=[contact]",
                     "downstream={'max_iters': 1}")
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads((folder / "reports" / "limb" / "summary.json").read_text())["poses"]


def test_a_library_at_1e_minus_30_or_1e_plus_30_repairs_as_at_1(tmp_path):
    """A pose of the demo limb at 1e-30, 1 and 1e+30 (at 1e-30 the contact solver once ended in ipctk's "unable
    to project matrix onto positive semi-definite cone" after 85,000 "Small gap" warnings): S0 and the contact repair
    give the same status and intersecting-face counts, and deviations in d equal within 1e-7 (the solvers work in
    the reference's unit, a power of two that scales exactly, but the key frames are stored to float32 precision of
    their offsets from the linear blend, and a scaled pose's offsets may round to the neighbouring float32: about
    1e-9 d, which the contact finish moves the free region's farthest vertex by up to ten times, 1.5e-8 d at 1e+30)."""
    runs = {scale: _limb_summary(tmp_path / f"{scale:g}", scale) for scale in (1.0, 1e-30, 1e30)}
    for scale in (1e-30, 1e30):
        assert len(runs[1.0]) == len(runs[scale]) == 1
        for ours, theirs in zip(runs[1.0], runs[scale]):
            assert ours["status"] == theirs["status"] and ours["pose"] == theirs["pose"]
            pairs = [(ours, theirs), (ours["repairs"]["contact"], theirs["repairs"]["contact"])]
            for a, b in pairs:
                assert a["intersecting_faces"] == b["intersecting_faces"], (scale, ours["pose"])
                assert a["deviation"] == pytest.approx(b["deviation"], rel=0, abs=1e-7), (scale, ours["pose"])


def test_a_pose_that_fails_now_is_not_taken_as_finished_from_an_earlier_runs_files(tmp_path):
    """ball-02 repaired, then made unreadable: the second run fails in its validate and leaves its earlier artifacts
    in place (verify.h5, the repaired mesh). Finished means finished by this code and these inputs (Snakemake's own
    rerun triggers), not that the files exist: the partial summary lists ball-02 as failed, not as repaired."""
    library = tmp_path / "lib"
    V, F = icosphere(2)
    write_mesh(library / "ball-reference.obj", V, F)
    write_mesh(library / "ball-01.obj", V * [1.2, 1.0, 0.9], F)
    write_mesh(library / "ball-02.obj", V * [0.9, 1.1, 1.0], F)
    assert snakemake(tmp_path, SUMMARY, "--config", f"library={library}", "repairs=[]").returncode == 0
    nan = V * [0.9, 1.1, 1.0]
    nan[3, 1] = np.nan
    write_mesh(library / "ball-02.obj", nan, F)
    proc = snakemake(tmp_path, SUMMARY, "--config", f"library={library}", "repairs=[]")
    assert proc.returncode == 1 and (tmp_path / "results" / "lib" / "ball-02" / "verify.h5").exists(), proc.stderr
    summary = json.loads((tmp_path / "reports" / "lib" / "summary.json").read_text())
    assert [e["pose"] for e in summary["poses"]] == ["ball-01"], proc.stderr[-3000:]
    assert [e["pose"] for e in summary["failed"]] == ["ball-02"] and "vertex 3" in summary["failed"][0]["error"]


def _bad_poses(library, V, F):
    """Pose files that cannot be repaired, each in its own way: {file name: what its error line must say}."""
    far = V.copy()
    far[7] = 1e30
    flipped = F.copy()
    flipped[0] = flipped[0, ::-1]
    nan = V.copy()
    nan[3, 1] = np.nan
    write_mesh(library / "far.obj", far, F)
    write_mesh(library / "flipped.obj", V, flipped)
    write_mesh(library / "fewer.obj", V[:-1], F[F.max(axis=1) < len(V) - 1])
    write_mesh(library / "nan.obj", nan, F)
    (library / "empty.obj").write_text("")
    (library / "binary.obj").write_bytes(bytes(range(256)) * 4)
    (library / "index.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    (library / "truncated.obj").write_text("v 0 0 0\nv 1 0\n")
    return {"far.obj": "vertex 7", "flipped.obj": "face", "fewer.obj": "vertices", "nan.obj": "vertex 3",
            "empty.obj": "empty", "binary.obj": "binary", "index.obj": "face vertex index 9",
            "truncated.obj": "line 2"}


def test_bad_poses_among_good_ones_each_fail_in_one_line_and_the_good_ones_are_repaired(tmp_path):
    """Eight broken pose files beside two good ones: one error line each, naming the file (no traceback); the
    good poses are repaired and in the summary, the broken ones listed there as failed; the run exits 1."""
    library = tmp_path / "lib"
    V, F = icosphere(2)
    write_mesh(library / "ball-reference.obj", V, F)
    write_mesh(library / "ball-01.obj", V * [1.2, 1.0, 0.9], F)
    write_mesh(library / "ball-02.obj", V * [0.9, 1.1, 1.0], F)
    bad = _bad_poses(library, V, F)
    proc = snakemake(tmp_path, SUMMARY, "--config", f"library={library}", "repairs=[]")
    assert proc.returncode == 1 and "Traceback" not in proc.stderr, proc.stderr[-3000:]
    lines = proc.stderr.splitlines()
    for name, says in bad.items():
        # the recap at the end, from the job's log file: once; the stage's own line, as it failed: at most once (a
        # full `make test` on 2 processes once lost one from Snakemake's merged output, its log file had it)
        recap = [line for line in lines if line.startswith(f"posefix: failed in validate: {library / name}: ")]
        named = [line for line in lines if line.startswith(f"posefix validate: error: {library / name}: ")]
        mentions = "\n".join(line for line in lines if name in line)  # in full, not cut
        assert len(recap) == 1 and says in recap[0] and len(named) <= 1, f"{name}: stderr lines naming it:\n" \
                                                                          f"{mentions}"
    summary = json.loads((tmp_path / "reports" / "lib" / "summary.json").read_text())
    assert [e["pose"] for e in summary["poses"]] == ["ball-01", "ball-02"]
    assert sorted(e["pose"] for e in summary["failed"]) == sorted(Path(n).stem for n in bad)
    for pose in ("ball-01", "ball-02"):
        assert (tmp_path / "results" / "lib" / "repaired" / f"{pose}.obj").exists()


def test_poses_whose_names_a_shell_would_split_are_repaired_under_their_own_names(tmp_path):
    """Spaces, quotes, a dollar sign, a semicolon and non-ASCII letters in pose file names: every pose is repaired,
    its repaired file and summary entry under the name it came with."""
    library = tmp_path / "lib"
    V, F = icosphere(2)
    write_mesh(library / "ball-reference.obj", V, F)
    names = ["walk 2", "it's $HOME;a", 'sauté "hi"']  # a space, quotes, a dollar sign, a semicolon, non-ASCII
    for i, name in enumerate(names):
        write_mesh(library / f"{name}.obj", V * [1.0 + 0.05 * i, 1.0, 0.95], F)
    proc = snakemake(tmp_path, SUMMARY, "--config", f"library={library}", "repairs=[]")
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr[-3000:]
    summary = json.loads((tmp_path / "reports" / "lib" / "summary.json").read_text())
    assert sorted(e["pose"] for e in summary["poses"]) == sorted(names)
    for name in names:
        assert (tmp_path / "results" / "lib" / "repaired" / f"{name}.obj").exists(), name
