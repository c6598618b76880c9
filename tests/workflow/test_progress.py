"""A run's progress from Snakemake's output: the number of jobs, every tenth done, what runs while nothing ends."""

from posefix.workflow.progress import RunProgress


class Clock:
    """A clock the test moves (seconds)."""

    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def job_lines(rule, jobid, pose):
    """Snakemake's lines for a job it starts (a local rule of a pose, or a rule without wildcards)."""
    lines = ["", "[Sat Dec  5 11:30:36 2026]", f"localrule {rule}:", f"    output: results/x/{pose}/{rule}.h5",
             f"    jobid: {jobid}"]
    return lines + ([f"    wildcards: pose={pose}"] if pose else []) + ["    resources: tmpdir=/tmp, mem_mb=1000"]


def finished_lines(jobid, rule, done, total):
    return ["[Sat Dec  5 11:30:44 2026]", f"Finished jobid: {jobid} (Rule: {rule})",
            f"{done} of {total} steps ({100 * done // total}%) done"]


def feed(progress, lines):
    return [shown for line in lines for shown in progress.feed(line)]


def test_a_run_of_500_jobs_says_its_progress_in_a_dozen_lines_naming_what_runs():
    progress = RunProgress(clock=Clock())
    shown = feed(progress, ["Job stats:", "job      count", "-----  -------", "fit        250", "verify     250",
                            "total            500"])
    assert shown == ["posefix: 500 jobs to run"]
    shown += feed(progress, job_lines("fit", 0, "pose-000"))
    for k in range(500):  # job k + 1 starts before job k ends
        next_job = job_lines("fit", k + 1, f"pose-{k + 1:03d}") if k + 1 < 500 else []
        shown += feed(progress, next_job + finished_lines(k, "fit", k + 1, 500))
    assert len(shown) == 11 and shown[-1] == "posefix: 500 of 500 jobs done (100%)", shown
    assert shown[1] == "posefix: 50 of 500 jobs done (10%); running: fit pose-050", shown


def test_while_no_job_ends_it_says_which_stage_runs_on_which_pose_and_for_how_long():
    clock = Clock()
    progress = RunProgress(clock=clock, quiet=60.0)
    feed(progress, ["total 3", *job_lines("summary", 7, None), *finished_lines(7, "summary", 1, 3)])
    feed(progress, job_lines("downstream", 5, "demo-03") + job_lines("render", 6, "demo-04"))
    clock.now = 30.0
    assert progress.idle() == []
    clock.now = 200.0
    assert progress.idle() == ["posefix: 1 of 3 jobs done (33%); running: downstream demo-03 for 3 min, "
                               "render demo-04 for 3 min"]
    clock.now = 230.0
    assert progress.idle() == []  # said 30 s ago
    feed(progress, finished_lines(5, "downstream", 2, 3) + finished_lines(6, "render", 3, 3))
    clock.now = 1000.0
    assert progress.idle() == []  # nothing runs


def test_more_jobs_running_than_it_names_are_counted():
    progress = RunProgress(clock=Clock(), shown=2)
    feed(progress, ["total 40"] + [line for k in range(5) for line in job_lines("fit", k, f"p{k}")])
    assert progress.feed("4 of 40 steps (10%) done") == [
        "posefix: 4 of 40 jobs done (10%); running: fit p0, fit p1 (and 3 more)"]


def test_a_failed_job_no_longer_runs_and_an_unpacked_pose_is_named():
    progress = RunProgress(clock=Clock())
    unpack = [line.replace("pose=", "member=") for line in job_lines("unpack", 3, "walk-2")]
    feed(progress, ["total 40", *unpack, *job_lines("fit", 4, "walk-1")])
    assert progress.feed("4 of 40 steps (10%) done") == [
        "posefix: 4 of 40 jobs done (10%); running: unpack walk-2, fit walk-1"]
    feed(progress, ["[Sat Dec  5 11:30:44 2026]", "Error in rule unpack:", "    message: None", "    jobid: 3",
                    "    input: walk.usda", "    output: results/walk/poses/walk-2.ply"])
    assert progress.feed("8 of 40 steps (20%) done") == ["posefix: 8 of 40 jobs done (20%); running: fit walk-1"]
