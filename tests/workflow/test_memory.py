"""The memory the rules ask for: measured lines with a margin and a floor, and the refusal of what cannot fit."""

import pytest

from posefix.workflow.memory import FLOOR_MB, MARGIN, OTHER_MB, PEAK_MB, memory_problem, stage_memory_mb


def test_a_stage_asks_for_its_measured_line_with_the_margin_and_never_less_than_the_floor():
    base, per_thousand = PEAK_MB["classify"]
    assert stage_memory_mb("classify", 0) == FLOOR_MB
    assert stage_memory_mb("classify", 200_000) == int(MARGIN * (base + 200 * per_thousand))
    assert stage_memory_mb("an_authoring_stage", 200_000) == int(MARGIN * (OTHER_MB[0] + 200 * OTHER_MB[1]))


@pytest.mark.parametrize("stage", sorted(PEAK_MB))
def test_no_stage_asks_for_more_than_linear_growth(stage):
    """Doubling the mesh at most doubles what a stage asks for (above the floor)."""
    for n in (10_000, 60_000, 240_000):
        assert stage_memory_mb(stage, n) <= stage_memory_mb(stage, 2 * n) <= 2 * max(stage_memory_mb(stage, n),
                                                                                      FLOOR_MB)


def test_what_cannot_fit_is_said_with_the_stage_that_needs_most():
    assert memory_problem(5000, 0) is None  # no limit
    assert memory_problem(5000, 100_000) is None
    stage = max(PEAK_MB, key=lambda s: stage_memory_mb(s, 240_000))
    need = stage_memory_mb(stage, 240_000)
    line = memory_problem(240_000, 6000)
    assert line.startswith(f"240000 vertices need about {need / 1000:.1f} GB in stage {stage}, more than the 6.0 GB "
                           "this run may use: ")
    assert memory_problem(240_000, need) is None
