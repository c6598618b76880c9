"""The downstream check: handles, and the grid of runs towards both examples."""

import subprocess
import sys
import time

import numpy as np
import psutil
import pytest

from test_gauss_newton import _bend, _strip
from posefix.downstream.check import EXAMPLES, downstream_check, handle_vertices


def test_handles_are_far_apart_and_deterministic():
    V, F = _strip()
    h = handle_vertices(V)
    assert len(set(h.tolist())) == 3 and h.tolist() == handle_vertices(V).tolist()
    assert np.linalg.norm(V[h[0]] - V[h[1]]) == pytest.approx(np.linalg.norm(V.max(0) - V.min(0)))


def test_grid_runs_every_setting_towards_both_examples_in_order():
    V, F = _strip()
    examples = {"original": _bend(V, 1.0, at=3.0), "repaired": _bend(V, 0.5, at=3.0)}
    check = downstream_check(V, F, examples, alphas=(1.0,), k_bend=(1e-2, 1e-1))
    assert check.grid == [(1.0, 1e-2, 0), (1.0, 1e-2, 1), (1.0, 1e-1, 0), (1.0, 1e-1, 1)]
    data, metrics = check.datasets(), check.metrics()
    assert data["converged"].all() and metrics["runs"] == 4 and EXAMPLES == ("original", "repaired")
    assert metrics["original_converged"] == metrics["repaired_converged"] == 2
    assert np.array_equal(np.diff(data["error_offsets"]), data["iterations"] + 1)
    assert metrics["original_iterations"] == data["iterations"][data["example"] == 0].sum()
    assert [c["example"] for c in check.curves()] == ["original", "repaired"] * 2


def test_another_repair_is_a_third_example_over_the_same_grid():
    V, F = _strip()
    examples = {"original": _bend(V, 1.0, at=3.0), "repaired": _bend(V, 0.5, at=3.0), "medial": _bend(V, 0.5, at=3.0)}
    check = downstream_check(V, F, examples, alphas=(1.0,), k_bend=(1e-2, 1e-1))
    assert check.grid == [(1.0, k, e) for k in (1e-2, 1e-1) for e in (0, 1, 2)]
    data, metrics = check.datasets(), check.metrics()
    assert data["examples"].tolist() == ["original", "repaired", "medial"] and metrics["runs"] == 6
    # the other repair's pose equals the repaired one here: its runs are the repaired runs, step for step
    assert np.array_equal(data["iterations"][data["example"] == 2], data["iterations"][data["example"] == 1])
    assert (metrics["medial_converged"], metrics["medial_iterations"]) == (metrics["repaired_converged"],
                                                                           metrics["repaired_iterations"])
    assert [c["example"] for c in check.curves()] == ["original", "repaired", "medial"] * 2


def test_runs_in_parallel_give_the_serial_results_bit_for_bit(monkeypatch):
    monkeypatch.setattr("posefix.downstream.check.SPAWN_MIN_VERTICES", 0)  # spawned for a small strip too
    V, F = _strip()
    examples = {"original": _bend(V, 1.0, at=3.0), "repaired": _bend(V, 0.5, at=3.0)}
    serial = downstream_check(V, F, examples, alphas=(0.5, 1.0), k_bend=(1e-2,))
    parallel = downstream_check(V, F, examples, alphas=(0.5, 1.0), k_bend=(1e-2,), workers=3)
    assert parallel.grid == serial.grid
    for a, b in zip(parallel.runs, serial.runs):
        assert a.V.tobytes() == b.V.tobytes() and a.errors.tobytes() == b.errors.tobytes()
        assert (a.reason, a.gradient_reduction, a.min_area_ratio) == (b.reason, b.gradient_reduction, b.min_area_ratio)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="workers die with their parent on Linux (prctl)")
def test_no_worker_outlives_its_parent_killed_with_sigkill(tmp_path):
    """A process running the check's runs on 2 workers (here runs that sleep a minute) is killed with SIGKILL, as
    a stage's parent can be: 2 s later no worker is left running (issue 50)."""
    script = tmp_path / "runs.py"
    script.write_text("import time\nfrom posefix.workflow.processes import ordered_map\n"
                      "if __name__ == '__main__':\n    list(ordered_map(time.sleep, [(60,), (60,)], 2))\n")
    parent = psutil.Process(subprocess.Popen([sys.executable, str(script)]).pid)
    deadline = time.monotonic() + 60
    while len(workers := [c for c in parent.children() if "spawn_main" in " ".join(c.cmdline())]) < 2:
        assert time.monotonic() < deadline, "the workers did not start"
        time.sleep(0.1)
    time.sleep(3.0)  # they have started sleeping (killed before, they exit as well: their parent is gone)
    parent.kill()
    parent.wait(10)
    time.sleep(2.0)
    left = [w.pid for w in workers if w.is_running() and w.status() != psutil.STATUS_ZOMBIE]
    assert not left, f"workers {left} outlived their parent"
