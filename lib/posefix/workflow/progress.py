"""A run's progress in a few lines, from Snakemake's output: jobs done of the total at every tenth, and, while
nothing finishes for a while, which stage runs on which pose and for how long.

Snakemake prints a block per job it starts (``rule verify:`` or ``localrule verify:``, ``jobid: 35``,
``wildcards: pose=lion-05``), ``Finished jobid: 35 (Rule: verify)`` and ``3 of 39 steps (8%) done`` when it ends,
and a table of the jobs to run (``Job stats:`` ... ``total  39``). :class:`RunProgress` reads those lines and
says what a user needs: ``posefix: 39 jobs to run`` once, ``posefix: 12 of 39 jobs done (31%); running: verify
lion-05, fit lion-06`` when a tenth more is done, and the same with how long each has run (``verify lion-05 for
3 min``) when nothing has been said for ``quiet`` seconds.

Examples
--------
>>> progress = RunProgress(clock=lambda: 0.0)
>>> progress.feed("total            10")
['posefix: 10 jobs to run']
>>> [progress.feed(line) for line in ("localrule verify:", "    jobid: 3", "    wildcards: pose=a")]
[[], [], []]
>>> progress.feed("1 of 10 steps (10%) done")
['posefix: 1 of 10 jobs done (10%); running: verify a']
"""

import re
import time

_RULE = re.compile(r"^(?:local)?rule (\w+):$")
_JOBID = re.compile(r"^\s+jobid: (\d+)$")
_POSE = re.compile(r"^\s+wildcards: .*\b(?:pose|member)=([^,]+)")  # member: rule unpack's pose (or reference)
_ERROR = re.compile(r"^Error in rule \w+:$")
_FINISHED = re.compile(r"^Finished jobid: (\d+)")
_STEPS = re.compile(r"^(\d+) of (\d+) steps \((\d+)%\) done")
_TOTAL = re.compile(r"^total\s+(\d+)$")


class RunProgress:
    """The progress lines of one Snakemake run, fed its output line by line.

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
        self._rule = self._job = None
        self._error = False  # in an "Error in rule" block: its jobid is a job that has ended
        self._tenth, self._done = 0, (0, 0, 0)
        self._said = clock()

    def feed(self, line):
        """The progress lines (list of str) that Snakemake's output ``line`` calls for."""
        line = line.rstrip("\n")
        rule, job, pose = _RULE.match(line), _JOBID.match(line), _POSE.match(line)
        finished, steps, total = _FINISHED.match(line), _STEPS.match(line), _TOTAL.match(line)
        if rule or _ERROR.match(line):
            self._rule, self._error = (rule.group(1), False) if rule else (None, True)
        elif job and self._error:
            self.running.pop(int(job.group(1)), None)
            self._error = False
        elif job and self._rule:
            self._job = int(job.group(1))
            self.running[self._job] = [self._rule, None, self.clock()]
        elif pose and self._job in self.running:
            self.running[self._job][1] = pose.group(1).strip()
        elif finished:
            self.running.pop(int(finished.group(1)), None)
        elif total:
            return self._say(f"posefix: {total.group(1)} jobs to run")
        elif steps:
            self._done = done, count, percent = tuple(map(int, steps.groups()))
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
