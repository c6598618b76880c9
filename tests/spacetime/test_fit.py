"""Greedy fit: reaches eps on smooth fields, selection rules, resume equals uninterrupted."""

import json
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

from conftest import ROOT, run_stage, smooth_field_problem
from posefix.io.artifacts import write_artifact
from posefix.spacetime.fit import (FitSettings, _diameter_pair, farthest_points, iterate, resume_fit, start_fit,
                                   truncate_history)
from posefix.spacetime.factorization import FactorizationError




def test_greedy_fit_reaches_eps_on_a_smooth_field():
    Y, V = smooth_field_problem()
    fit = start_fit(Y, V, FitSettings(eps=1e-4, max_centers=2000, batch=64, candidates=256))
    assert iterate(fit) == "eps"
    assert fit.history[-1]["max_error"] < 1e-4 and fit.n < 2000
    assert np.abs(fit.field()(Y) - V).max() < 1e-4  # the returned field is the one measured
    errors = [r["max_error"] for r in fit.history]
    assert errors[-1] < errors[0] / 100
    assert all(r["condition"] > 1 for r in fit.history)


def test_stop_reasons_max_centers_and_rms():
    Y, V = smooth_field_problem(800)
    fit = start_fit(Y, V, FitSettings(eps=0.0, max_centers=300, batch=64))
    assert iterate(fit) == "max_centers" and fit.n == 300
    fit = start_fit(Y, V, FitSettings(eps=0.0, eps_rms=1e-3, max_centers=800, batch=64))
    assert iterate(fit) == "rms" and fit.history[-1]["rms_error"] < 1e-3


def test_seed_starts_from_the_two_most_distant_points():
    Z = np.array([[0.0, 0, 0, 0], [1.0, 0, 0, 0], [0.5, 0, 0, 0], [5.0, 0, 0, 0], [-4.0, 0, 0, 0]])
    assert sorted(_diameter_pair(Z)) == [3, 4]
    assert farthest_points(Z, 3, [3, 4]).tolist() == [3, 4, 2]  # 0.5 is 4.5 from both ends
    assert farthest_points(Z, 5, [0]).tolist() == [0, 3, 4, 1, 2]


@pytest.mark.parametrize("selection", ["fps", "worst"])
def test_selection_takes_the_worst_first(selection):
    Y, V = smooth_field_problem(1500)
    fit = start_fit(Y, V, FitSettings(eps=0.0, max_centers=400, batch=64, candidates=256, selection=selection))
    iterate(fit)
    fit2 = start_fit(Y, V, FitSettings(eps=0.0, max_centers=192, batch=64, candidates=256, selection=selection))
    iterate(fit2)
    err = np.linalg.norm(fit2.residual, axis=1)
    err[fit2.order] = -np.inf
    worst = int(np.argmax(err))
    fit3 = start_fit(Y, V, FitSettings(eps=0.0, max_centers=256, batch=64, candidates=256, selection=selection))
    iterate(fit3)
    assert fit3.order[192] == worst  # the next batch begins with the worst constraint
    if selection == "worst":
        assert set(fit3.order[192:]) == set(np.argsort(-err)[:64])
    else:  # farthest points within the 256 worst
        assert set(fit3.order[192:]) <= set(np.argsort(-err)[:256])
    assert np.array_equal(fit.order[:256], fit3.order)  # prefixes: the sequence does not depend on the cap


@pytest.mark.parametrize("update", ["blocked", "full"])
def test_resume_equals_uninterrupted(update):
    Y, V = smooth_field_problem(1200)
    settings = FitSettings(eps=1e-5, max_centers=700, batch=64, candidates=256, update=update)
    whole = start_fit(Y, V, settings)
    iterate(whole)
    part = start_fit(Y, V, FitSettings(**{**settings.__dict__, "max_centers": 320}))
    iterate(part)
    # as if killed after the 320-centre record: resume from its state with the full settings
    keep = truncate_history(part.history, settings)
    assert part.history[keep - 1]["centers"] == 320
    resumed = resume_fit(Y, V, settings, part.state(), part.history[:keep])
    iterate(resumed)
    assert np.array_equal(resumed.order, whole.order)
    assert np.array_equal(resumed.weights, whole.weights) and np.array_equal(resumed.poly, whole.poly)


def test_truncate_history_for_other_stopping_rules():
    Y, V = smooth_field_problem(1200)
    base = FitSettings(eps=1e-5, max_centers=700, batch=64, candidates=256)
    fit = start_fit(Y, V, base)
    iterate(fit)
    history = fit.history
    # a larger eps stops at the first record below it
    eps = history[4]["max_error"] * 1.0001
    k = truncate_history(history, FitSettings(**{**base.__dict__, "eps": eps}))
    assert history[k - 1]["max_error"] < eps and all(r["max_error"] >= eps for r in history[:k - 1])
    # a smaller cap that cuts a batch: keep only whole batches below it
    assert history[truncate_history(history, FitSettings(**{**base.__dict__, "max_centers": 300})) - 1]["centers"] == 256
    # a different batch size: nothing is reusable
    assert truncate_history(history, FitSettings(**{**base.__dict__, "batch": 32})) == 0


def _constraints_file(path, n=3000):
    Y, V = smooth_field_problem(n, seed=3)
    write_artifact(path, "constraints", {"points": Y, "values": V}, params={}, inputs=[], timings={},
                   metrics={"bbox_diagonal": 1.0, "tau": 0.3, "samples": 12, "constraint_vertices": 250})


def _fit_args(constraints, out, ckpt):
    return ["--constraints", constraints, "--out", out, "--checkpoint", ckpt, "--eps-rel", "1e-9",
            "--max-centers", "1500", "--batch", "64", "--candidates", "256"]


def test_fit_stage_killed_and_rerun_continues_to_the_same_result(tmp_path):
    _constraints_file(tmp_path / "constraints.h5")
    run_stage("fit", *_fit_args(tmp_path / "constraints.h5", tmp_path / "whole.h5", tmp_path / "whole.ckpt"))
    ckpt = tmp_path / "fit.ckpt"
    proc = subprocess.Popen([sys.executable, str(ROOT / "stages" / "fit.py"),
                             *map(str, _fit_args(tmp_path / "constraints.h5", tmp_path / "fit.h5", ckpt))],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 120
    while time.time() < deadline:
        try:
            if len(json.loads((ckpt / "meta.json").read_text())["history"]) >= 4:
                break
        except (OSError, ValueError):
            pass
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert not (tmp_path / "fit.h5").exists()
    committed = len(json.loads((ckpt / "meta.json").read_text())["history"])
    assert 4 <= committed < 23  # killed mid-fit
    log = run_stage("fit", *_fit_args(tmp_path / "constraints.h5", tmp_path / "fit.h5", ckpt),
                    "--keep-checkpoint").stderr
    assert "resuming from checkpoint" in log
    assert not (tmp_path / "whole.ckpt").exists() and (ckpt / "meta.json").exists()  # removed unless kept
    with h5py.File(tmp_path / "fit.h5", "r") as a, h5py.File(tmp_path / "whole.h5", "r") as b:
        assert a["metrics"].attrs["resumed_iterations"] >= 4
        for name in ("center_index", "weights", "poly", "history/max_error"):
            assert np.array_equal(a[name][()], b[name][()]), name


def test_constraints_near_one_quadric_are_refused_at_the_first_solve():
    """Points of a sphere scaled uniformly over time, rounded to float32 (|x|^2 = (1 + t / 10)^2: a quadric of
    space-time, 1e-8 off): the start's exact-quadric check passes them, and the first solve's condition number is
    beyond MAX_CONDITION (before: NaN path lines from the fitted field)."""
    rng = np.random.default_rng(1)
    x = rng.normal(size=(1500, 3))
    t = rng.uniform(0, 1, size=(1500, 1))
    Y = np.hstack([(x / np.linalg.norm(x, axis=1, keepdims=True)) * (1 + 0.1 * t), t]).astype(np.float32)
    fit = start_fit(Y.astype(np.float64), 0.1 * Y[:, :3].astype(np.float64), FitSettings(eps=1e-9, batch=64))
    with pytest.raises(FactorizationError, match=r"nearly singular at 64 centres \(condition number .*, beyond 1e\+13\)"):
        iterate(fit)
