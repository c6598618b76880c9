"""A run's progress in a few lines, from Snakemake's events (:mod:`posefix.workflow.events`): jobs done of the total
at every tenth, and, while nothing finishes for a while, which stage runs on which pose and for how long.

Snakemake says how many jobs it will run (``run_info``, its ``stats``), which it starts (``job_info``: jobid, rule,
wildcards), which end (``job_finished``, or ``job_error``) and how many are done (``progress``). :class:`RunProgress`
reads those events and says what a user needs: ``posefix: 39 jobs to run`` once, ``posefix: 12 of 39 jobs done
(31%); running: verify lion-05, fit lion-06`` when a tenth more is done, and the same with how long each has run
(``verify lion-05 for 3 min``) when nothing has been said for ``quiet`` seconds.

Examples
--------
>>> progress = RunProgress(clock=lambda: 0.0)
>>> progress.feed({"event": "run_info", "stats": {"verify": 10, "total": 10}})
['posefix: 10 jobs to run']
>>> progress.feed({"event": "job_info", "jobid": 3, "rule_name": "verify", "wildcards": {"pose": "a"}})
[]
>>> progress.feed({"event": "progress", "done": 1, "total": 10})
['posefix: 1 of 10 jobs done (10%); running: verify a']
"""

import time

POSE_WILDCARDS = ("pose", "member")
"""The wildcards that name a job's pose (``member``: rule unpack's pose, or the reference)."""


class RunProgress:
    """The progress lines of one Snakemake run, fed its events one by one.

    Parameters
    ----------
    clock : callable, optional
        Seconds (float), monotonic.
    quiet : float, optional
        Seconds without a progress line after which :meth:`idle` says what runs, and for how long.
    shown : int, optional
        Running jobs named in a line at most (the others counted).
    """

    def __init__(self, clock=time.monotonic, quiet=60.0, shown=3):
        self.clock, self.quiet, self.shown = clock, quiet, shown
        self.running = {}  # jobid -> [rule, pose or None, start seconds]
        self._tenth, self._done = 0, (0, 0, 0)
        self._said = clock()

    def feed(self, event):
        """The progress lines (list of str) that Snakemake's ``event`` (dict, :func:`~posefix.workflow.events.
        snakemake_event`) calls for."""
        kind = event["event"]
        if kind == "run_info" and "total" in event.get("stats", {}):
            return self._say(f"posefix: {event['stats']['total']} jobs to run")
        if kind == "job_info":
            wildcards = event.get("wildcards", {})
            pose = next((wildcards[name] for name in POSE_WILDCARDS if name in wildcards), None)
            self.running[event["jobid"]] = [event["rule_name"], pose, self.clock()]
        elif kind in ("job_finished", "job_error"):
            self.running.pop(event.get("job_id", event.get("jobid")), None)
        elif kind == "progress" and event.get("total"):
            done, count = event["done"], event["total"]
            self._done = done, count, percent = done, count, 100 * done // count
            if percent // 10 > self._tenth or done == count:
                self._tenth = percent // 10
                return self._say(f"posefix: {done} of {count} jobs done ({percent}%)" + self._running(False))
        return []

    def idle(self):
        """A line (list of one str) saying what runs and for how long when nothing was said for ``quiet`` s;
        else ``[]``."""
        if not self.running or self.clock() - self._said < self.quiet:
            return []
        done, count, percent = self._done
        head = f"posefix: {done} of {count} jobs done ({percent}%)" if count else "posefix: working"
        return self._say(head + self._running(True))

    def _running(self, durations):
        """``; running: verify a, fit b (and 2 more)``, with how long each has run when ``durations``; '' when
        none runs."""
        now = self.clock()
        jobs = sorted(self.running.values(), key=lambda job: job[2])
        names = [f"{rule} {pose}" if pose else rule for rule, pose, _ in jobs[:self.shown]]
        if durations:
            names = [f"{name} for {_duration(now - job[2])}" for name, job in zip(names, jobs)]
        more = f" (and {len(jobs) - self.shown} more)" if len(jobs) > self.shown else ""
        return f"; running: {', '.join(names)}{more}" if jobs else ""

    def _say(self, text):
        self._said = self.clock()
        return [text]


def _duration(seconds):
    """``42 s``, ``3 min``, ``1 h 05 min`` (str) for ``seconds`` (float)."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    minutes = int(seconds // 60)
    return f"{minutes} min" if minutes < 60 else f"{minutes // 60} h {minutes % 60:02d} min"
