"""Snakemake's events as posefix reads them: the log records Snakemake's logger emits (``record.event``: ``run_info``,
``job_info``, ``job_finished``, ``job_error``, ``progress``, ``error``, ...; `snakemake-interface-logger-plugins`),
each as a small dict of plain values, and from them a failed run's lines: the posefix error lines of the jobs that
failed (their log files, which the ``job_error`` events name) and, where no job left one, the run's one-line cause
(an ``error`` event: the exception Snakemake stopped with). No text of Snakemake's is parsed.

The ``posefix`` command gets the events through the logger plugin ``posefix`` (``snakemake_logger_plugin_posefix``:
one JSON object a line), a run in this process (the Snakefile's ``onerror``, ``posefix.repair_library``) through an
:class:`EventRecorder` on Snakemake's logger.

Examples
--------
>>> import logging
>>> record = logging.makeLogRecord({"msg": None, "event": "progress", "done": 3, "total": 9})
>>> snakemake_event(record)
{'event': 'progress', 'done': 3, 'total': 9}
>>> failure_line([{"event": "error", "exception": "LockException", "msg": "LockException:\\nError: ..."}], "/w")
'posefix: error: /w: another Snakemake run is working in this folder; wait for it to finish (if none is running: snakemake --unlock)'
"""

import logging
from pathlib import Path

FIELDS = ("jobid", "job_id", "rule_name", "wildcards", "log", "exception", "done", "total", "stats")
"""The attributes of Snakemake's records that an event keeps (those its consumers read)."""

KEPT = ("run_info", "job_info", "job_finished", "job_error", "progress", "error")
"""The events kept, the others (shell commands, resources, the DAG) left out."""

JOBS_FAILED = "At least one job did not complete successfully"
"""The message of the ``WorkflowError`` that ends a run whose jobs failed: not a cause in itself."""

CAUSES = (
    ("LockException", "{folder}: another Snakemake run is working in this folder; wait for it to finish (if none is "
                      "running: snakemake --unlock)"),
    ("No space left on device", "no space left on device ({cause}); free some disk, then run the same command again"),
    ("Permission denied", "permission denied ({cause})"),
    ("profile directory given", "Snakemake: {cause} (a --profile or SNAKEMAKE_PROFILE that names no profile)"),
)
"""Failures that precede or stop the jobs, in words: the text (an exception's name or its message's) and the line
(``folder``: the run's folder; ``cause``: the error's first line that names the text)."""


def snakemake_event(record):
    """The event of Snakemake's log ``record`` (logging.LogRecord) as a dict of plain values (``event``, ``msg`` when
    it says something, and the :data:`FIELDS` it has), or None for a record posefix does not read (:data:`KEPT`)."""
    event = str(getattr(record, "event", "") or "")
    if event not in KEPT:
        return None
    out = {"event": event}
    if record.msg is not None:
        out["msg"] = str(record.msg)
    for name in FIELDS:
        value = getattr(record, name, None)
        if value is not None:
            out[name] = dict(value) if name == "wildcards" else list(value) if name == "log" else value
    return out


class EventRecorder(logging.Handler):
    """A handler for Snakemake's logger that keeps its events (:func:`snakemake_event`) in ``self.events`` (list of
    dict), as they are emitted (no queue between: they are all there when the run ends)."""

    def __init__(self):
        super().__init__()
        self.events = []

    def emit(self, record):
        event = snakemake_event(record)
        if event is not None:
            self.events.append(event)


def record_events(logger=logging.getLogger("snakemake")):
    """The :class:`EventRecorder` on Snakemake's ``logger`` (logging.Logger), added on the first call (Snakemake
    parses the Snakefile, which calls this, after it has set its logger's handlers up)."""
    recorder = next((h for h in logger.handlers if isinstance(h, EventRecorder)), None)
    if recorder is None:
        recorder = EventRecorder()
        logger.addHandler(recorder)
    return recorder


def failed_job_errors(events, folder):
    """The posefix error lines of the jobs that failed (list of str), once each in order: read from the log files
    that their ``job_error`` events name (relative to ``folder``); ``[`` :func:`failure_line` ``]`` when none has
    one."""
    lines = []
    for event in events:
        for path in event.get("log", []) if event["event"] == "job_error" else []:
            try:
                text = (Path(folder) / path).read_text(errors="replace")
            except OSError:
                continue
            lines += [line for line in text.splitlines() if is_error_line(line)]
    return list(dict.fromkeys(lines)) or [failure_line(events, folder)]


def is_error_line(line):
    """Whether ``line`` (str) is a stage's posefix error line, ``posefix <stage>: error: ...``.

    Examples
    --------
    >>> is_error_line("posefix fit: error: a.h5: too few"), is_error_line("12:00:01 posefix fit: warning: x")
    (True, False)
    """
    head, _, rest = line.partition(": error:")
    words = head.split(" ")
    return bool(rest) and len(words) == 2 and words[0] == "posefix" and words[1].replace("-", "_").isidentifier()


def failure_line(events, folder, text=()):
    """The one-line cause of a run that failed with no posefix error line (str): the first ``error`` event other than
    the failed jobs' (:data:`JOBS_FAILED`, a rule's exception), in words where :data:`CAUSES` knows it; else the
    last ``Error:`` line of Snakemake's ``text`` (list of str: what it says before its logger starts, e.g. a
    profile it cannot read)."""
    for event in events:
        if event["event"] == "error" and event.get("exception") != "RuleException" and JOBS_FAILED not in event.get(
                "msg", ""):
            return "posefix: error: " + _in_words(event.get("exception", ""), event.get("msg", ""), folder)
    said = [line.strip() for line in text if line.startswith("Error: ")]
    if said:
        return "posefix: error: " + _in_words("", said[-1].removeprefix("Error: "), folder)
    return "posefix: error: the run failed before any stage reported (see Snakemake's full output below)"


def _in_words(exception, message, folder):
    """An error's one line (str) from its exception's name and message: the :data:`CAUSES` line that names it, else
    ``Name: why``, where Snakemake's message has the why on the line after its head (``WorkflowError:``,
    ``OSError in file F, line N:``), and the last line with it when the why ends with ``:`` (a list of files); a
    traceback's last line."""
    lines = [line.strip() for line in message.splitlines() if line.strip() not in ("", "None")] or [exception]
    for text, words in CAUSES:
        if text == exception or text in message:
            cause = next((part for line in lines for part in line.split(". ") if text in part), lines[0])
            return words.format(folder=folder, cause=cause.removesuffix(".")[:300])
    if lines[0].startswith("Traceback"):  # Python's: the exception on its last line
        return lines[-1][:300]
    why = [line for line in lines[1:] if not line.startswith('File "')]  # (not a traceback's lines)
    if not lines[0].endswith(":") or not why:
        return lines[0][:300]
    name = exception or lines[0].split(" ")[0].rstrip(":")
    return f"{name}: {why[0]}{f' {why[-1]}' if why[0].endswith(':') and len(why) > 1 else ''}"[:300]


def recap_line(line):
    """A failed job's posefix error line as the run's recap shows it at the end (``posefix validate: error: X`` ->
    ``posefix: failed in validate: X``): the error itself stays the one line that says ``error:``.

    Examples
    --------
    >>> recap_line("posefix validate: error: lib/b.obj: line 4"), recap_line("posefix: error: the run failed")
    ('posefix: failed in validate: lib/b.obj: line 4', 'posefix: error: the run failed')
    """
    if not is_error_line(line):
        return line
    head, _, rest = line.partition(": error: ")
    return f"posefix: failed in {head.split(' ')[1]}: {rest}"
