"""Snakemake's events through the logger plugin ``posefix``: recorded runs (``events/*.jsonl``: Snakemake's log
records as its logger emitted them, paths made relative) fed to the plugin, and the progress and failure lines that
the ``posefix`` command makes of what the plugin writes."""

import json
import logging
import subprocess
import sys
from pathlib import Path

import pytest
from snakemake_interface_logger_plugins.registry import LoggerPluginRegistry

from posefix.workflow.events import EventRecorder, failed_job_errors, record_events
from posefix.workflow.progress import RunProgress
from snakemake_logger_plugin_posefix import LogHandler, LogHandlerSettings

RECORDED = Path(__file__).parent / "events"


def recorded(name):
    """The log records of the recorded run ``name`` (list of logging.LogRecord)."""
    return [logging.makeLogRecord(json.loads(line)) for line in (RECORDED / f"{name}.jsonl").read_text().splitlines()]


def through_plugin(records, tmp_path):
    """The events (list of dict) that the plugin writes for ``records``, read back from its file."""
    path = tmp_path / "events.jsonl"
    handler = LogHandler(None, LogHandlerSettings(events=str(path)))
    for record in records:
        handler.emit(record)
    handler.close()
    return [json.loads(line) for line in path.read_text().splitlines()]


def test_snakemake_finds_the_plugin_by_its_name():
    assert LoggerPluginRegistry().get_plugin("posefix").log_handler is LogHandler


def test_importing_the_plugin_imports_no_posefix_module():
    """Snakemake imports every installed logger plugin when it starts, whatever the workflow: not posefix then."""
    code = "import sys, snakemake_logger_plugin_posefix; print(sorted(m for m in sys.modules if 'posefix.' in m))"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout == "[]\n"


def test_a_failed_run_gives_its_progress_and_the_failed_jobs_error_lines(tmp_path):
    """A library of two poses: validate refuses ball-02 (a face index out of range), fit refuses ball-01."""
    events = through_plugin(recorded("failed-poses"), tmp_path)
    assert {event["event"] for event in events} == {"run_info", "job_info", "job_finished", "job_error", "progress",
                                                    "error"}
    progress, lines = RunProgress(clock=lambda: 0.0), []
    for event in events:
        lines += progress.feed(event)
        if event["event"] == "job_info" and event["rule_name"] == "fit":
            assert progress.idle() == [] and progress.running  # (quiet for 60 s: not yet)
    assert lines == ["posefix: 25 jobs to run", "posefix: 3 of 25 jobs done (12%)", "posefix: 5 of 25 jobs done (20%)"]
    assert progress.running == {}  # the failed jobs ended too
    logs = tmp_path / "results" / "lib" / "logs"
    for pose, stage, line in (("ball-02", "validate", "lib/ball-02.obj: line 4: face vertex index 9 is out of range"),
                              ("ball-01", "fit", "lib/ball-01.obj: the constraint points do not determine it")):
        (logs / pose).mkdir(parents=True)
        (logs / pose / f"{stage}.log").write_text(f"11:02:39 posefix {stage}: read\nposefix {stage}: error: {line}\n")
    assert failed_job_errors(events, tmp_path) == [
        "posefix validate: error: lib/ball-02.obj: line 4: face vertex index 9 is out of range",
        "posefix fit: error: lib/ball-01.obj: the constraint points do not determine it"]
    assert failed_job_errors(events, tmp_path / "elsewhere") == [  # no log: the run's line
        "posefix: error: the run failed before any stage reported (see Snakemake's full output below)"]


@pytest.mark.parametrize("name, line", [
    ("locked", "{folder}: another Snakemake run is working in this folder; wait for it to finish (if none is "
               "running: snakemake --unlock)"),
    ("no-space", "no space left on device ([Errno 28] No space left on device: 'results/lib/ball-01/fit.h5'); free "
                 "some disk, then run the same command again"),
    ("permission", "permission denied ([Errno 13] Permission denied: 'results/demo')"),
    ("missing-input", "MissingInputException: Missing input files for rule b: nothere.txt"),
])
def test_a_run_that_stops_before_its_jobs_says_why_in_one_line(name, line, tmp_path):
    events = through_plugin(recorded(name), tmp_path)
    assert failed_job_errors(events, tmp_path) == [f"posefix: error: {line.format(folder=tmp_path)}"]


def test_the_recorder_in_the_process_keeps_the_same_events(tmp_path):
    logger = logging.getLogger("posefix-test-snakemake")
    recorder = record_events(logger)
    assert record_events(logger) is recorder and isinstance(recorder, EventRecorder)  # once
    try:
        for record in recorded("failed-poses"):
            logger.handle(record)
    finally:
        logger.removeHandler(recorder)
    assert recorder.events == through_plugin(recorded("failed-poses"), tmp_path)
