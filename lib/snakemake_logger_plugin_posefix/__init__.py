"""Snakemake's logger plugin ``posefix``: the events the ``posefix`` command reads (:mod:`posefix.workflow.events`),
one JSON object a line, appended to the file that ``--logger-posefix-events`` names (the command gives a pipe's
``/dev/fd/N``).

``snakemake --logger posefix --logger-posefix-events events.jsonl`` runs it by hand; Snakemake's own output is
unchanged (it neither writes to the terminal nor replaces Snakemake's log file). Importing it imports no posefix module:
Snakemake imports every installed logger plugin when it starts, for any workflow.
"""

import json
from dataclasses import dataclass, field
from typing import Optional

from snakemake_interface_logger_plugins.base import LogHandlerBase
from snakemake_interface_logger_plugins.settings import LogHandlerSettingsBase


@dataclass
class LogHandlerSettings(LogHandlerSettingsBase):
    events: Optional[str] = field(default=None, metadata={
        "help": "file the events are appended to, one JSON object a line (none: no events are written)"})


class LogHandler(LogHandlerBase):
    """Each event that posefix reads (:func:`~posefix.workflow.events.snakemake_event`) as one line of JSON, written
    at once (the command shows the progress as it comes)."""

    def __post_init__(self):
        from posefix.workflow.events import snakemake_event  # (here: Snakemake imports every installed plugin)
        self.event = snakemake_event
        path = self.settings.events if self.settings is not None else None
        self.stream = open(path, "a", encoding="utf-8", buffering=1) if path else None

    def emit(self, record):
        event = self.event(record)
        if event is not None and self.stream is not None:
            self.stream.write(json.dumps(event, default=str) + "\n")

    def close(self):
        if self.stream is not None:
            self.stream.close()
            self.stream = None
        super().close()

    @property
    def writes_to_stream(self):
        return False

    @property
    def writes_to_file(self):
        return False

    @property
    def has_filter(self):
        return True  # every event, whatever --quiet says: the command decides what it shows

    @property
    def has_formatter(self):
        return True

    @property
    def needs_rulegraph(self):
        return False
