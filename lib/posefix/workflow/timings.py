"""Wall seconds of stages: per sub-step while a stage runs, and per stage from Snakemake's benchmark files."""

import csv
import logging
import time
from contextlib import contextmanager
from pathlib import Path

log = logging.getLogger(__name__)


class Timings(dict):
    """Wall seconds per named sub-step; ``with timings.step("solve"): ...`` adds and logs one."""

    @contextmanager
    def step(self, name):
        """Time the block, add its seconds to ``self[name]`` and log them."""
        start = time.perf_counter()
        yield
        seconds = time.perf_counter() - start
        self[name] = self.get(name, 0.0) + seconds
        log.info("%s: %.3f s", name, seconds)


def benchmark_seconds(folder, stage):
    """Wall seconds from a Snakemake benchmark file ``folder/<stage>*.tsv`` (column ``s``), None when absent."""
    row = benchmark_row(folder, stage)
    return None if row is None else float(row["s"])


def benchmark_row(folder, stage):
    """The measurements of a Snakemake benchmark file ``folder/<stage>*.tsv`` (dict of str: ``s``, ``max_rss``
    in MB, ...), None when absent."""
    files = sorted(Path(folder).glob(f"{stage}*.tsv"))
    if not files:
        return None
    with open(files[0]) as fh:
        return next(csv.DictReader(fh, delimiter="\t"))
