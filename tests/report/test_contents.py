"""What the report holds: every figure has its caption, and the timed stages are rules with benchmarks."""

from conftest import ROOT
from posefix.report.contents import POSE_FIGURES, TIMED_STAGES


def test_every_pose_figure_has_a_caption_and_a_label():
    for name, label in POSE_FIGURES.items():
        assert (ROOT / "rules" / "captions" / f"{name}.rst").read_text().strip() and label


def test_timed_stages_are_rules_with_a_benchmark_file():
    rules = "".join(p.read_text() for p in (ROOT / "rules").glob("*.smk"))
    for stage in TIMED_STAGES:
        assert f"rule {stage}:" in rules and f'benchmark: benchmark_file("{stage}")' in rules  # (per pose)
