"""Stage timings: sub-steps add up and are logged; Snakemake benchmark files are read."""

import logging

from posefix.workflow.timings import Timings, benchmark_row, benchmark_seconds


def test_steps_add_up_under_their_name_and_are_logged(caplog):
    timings = Timings()
    with caplog.at_level(logging.INFO, logger="posefix.workflow.timings"):
        for _ in range(2):
            with timings.step("solve"):
                pass
    assert list(timings) == ["solve"] and timings["solve"] >= 0
    assert [r.getMessage().split(":")[0] for r in caplog.records] == ["solve", "solve"]


def test_benchmark_seconds(tmp_path):
    (tmp_path / "fit.tsv").write_text("s\th:m:s\tmax_rss\n12.5\t0:00:12\t100\n")
    assert benchmark_seconds(tmp_path, "fit") == 12.5 and benchmark_seconds(tmp_path, "verify") is None
    assert benchmark_row(tmp_path, "fit") == {"s": "12.5", "h:m:s": "0:00:12", "max_rss": "100"}
    assert benchmark_row(tmp_path, "verify") is None
