"""A run's progress from Snakemake's events: the number of jobs, every tenth done, what runs while nothing ends."""

from posefix.workflow.progress import RunProgress


class Clock:
    """A clock the test moves (seconds)."""

    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def started(rule, jobid, pose, wildcard="pose"):
    """Snakemake's event for a job it starts (of a pose, or of a rule without wildcards)."""
    return [{"event": "job_info", "jobid": jobid, "rule_name": rule, "wildcards": {wildcard: pose} if pose else {}}]


def finished(jobid, done, total):
    return [{"event": "job_finished", "job_id": jobid}, {"event": "progress", "done": done, "total": total}]


def jobs_to_run(total):
    return [{"event": "run_info", "stats": {"fit": total, "total": total}}]


def feed(progress, events):
    return [shown for event in events for shown in progress.feed(event)]


def test_a_run_of_500_jobs_says_its_progress_in_a_dozen_lines_naming_what_runs():
    progress = RunProgress(clock=Clock())
    shown = feed(progress, jobs_to_run(500))
    assert shown == ["posefix: 500 jobs to run"]
    shown += feed(progress, started("fit", 0, "pose-000"))
    for k in range(500):  # job k + 1 starts before job k ends
        next_job = started("fit", k + 1, f"pose-{k + 1:03d}") if k + 1 < 500 else []
        shown += feed(progress, next_job + finished(k, k + 1, 500))
    assert len(shown) == 11 and shown[-1] == "posefix: 500 of 500 jobs done (100%)", shown
    assert shown[1] == "posefix: 50 of 500 jobs done (10%); running: fit pose-050", shown


def test_while_no_job_ends_it_says_which_stage_runs_on_which_pose_and_for_how_long():
    clock = Clock()
    progress = RunProgress(clock=clock, quiet=60.0)
    feed(progress, [*jobs_to_run(3), *started("summary", 7, None), *finished(7, 1, 3)])
    feed(progress, started("downstream", 5, "demo-03") + started("render", 6, "demo-04"))
    clock.now = 30.0
    assert progress.idle() == []
    clock.now = 200.0
    assert progress.idle() == ["posefix: 1 of 3 jobs done (33%); running: downstream demo-03 for 3 min, "
                               "render demo-04 for 3 min"]
    clock.now = 230.0
    assert progress.idle() == []  # said 30 s ago
    feed(progress, finished(5, 2, 3) + finished(6, 3, 3))
    clock.now = 1000.0
    assert progress.idle() == []  # nothing runs


def test_more_jobs_running_than_it_names_are_counted():
    progress = RunProgress(clock=Clock(), shown=2)
    feed(progress, jobs_to_run(40) + [event for k in range(5) for event in started("fit", k, f"p{k}")])
    assert progress.feed({"event": "progress", "done": 4, "total": 40}) == [
        "posefix: 4 of 40 jobs done (10%); running: fit p0, fit p1 (and 3 more)"]


def test_a_failed_job_no_longer_runs_and_an_unpacked_pose_is_named():
    progress = RunProgress(clock=Clock())
    feed(progress, [*jobs_to_run(40), *started("unpack", 3, "walk-2", "member"), *started("fit", 4, "walk-1")])
    assert progress.feed({"event": "progress", "done": 4, "total": 40}) == [
        "posefix: 4 of 40 jobs done (10%); running: unpack walk-2, fit walk-1"]
    feed(progress, [{"event": "job_error", "jobid": 3, "rule_name": "unpack", "log": ["r/logs/unpack.log"]}])
    assert progress.feed({"event": "progress", "done": 8, "total": 40}) == [
        "posefix: 8 of 40 jobs done (20%); running: fit walk-1"]
