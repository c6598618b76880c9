"""Fit checkpoints: crash-safe commits, another key or a half-written iteration is ignored."""

import numpy as np
import pytest

from conftest import smooth_field_problem
from posefix.spacetime import fit_checkpoint as checkpoint
from posefix.io.errors import InputError
from posefix.spacetime.fit import FitSettings, iterate, start_fit


def test_checkpoint_ignores_another_key_and_a_half_written_iteration(tmp_path):
    Y, V = smooth_field_problem(600)
    fit = start_fit(Y, V, FitSettings(eps=0.0, max_centers=200, batch=64))
    previous = None

    def save(fit, record):
        nonlocal previous
        previous = checkpoint.save_iteration(tmp_path, "k1", {}, fit, previous)

    iterate(fit, on_iteration=save)
    (tmp_path / "iter-00009.npz.tmp").write_bytes(b"half")  # a write interrupted by a kill
    state, history = checkpoint.load(tmp_path, "k1")
    assert len(history) == len(fit.history) and np.array_equal(state["order"], fit.order)
    assert checkpoint.load(tmp_path, "other") == (None, [])
    (tmp_path / "iter-00001.npz").unlink()
    assert checkpoint.load(tmp_path, "k1") == (None, [])


def test_a_resumed_fit_continues_exactly_as_an_uninterrupted_one(tmp_path):
    Y, V = smooth_field_problem(600)
    short, longer = FitSettings(eps=0.0, max_centers=200, batch=64), FitSettings(eps=0.0, max_centers=330, batch=64)
    fit, resumed = checkpoint.start_or_resume(Y, V, short, tmp_path, "k")
    assert resumed == 0
    iterate(fit, on_iteration=checkpoint.committer(tmp_path, "k", {}, fit, resumed))
    again, resumed = checkpoint.start_or_resume(Y, V, longer, tmp_path, "k")
    assert 0 < resumed < len(fit.history)  # the short fit's last, cut batch is not one the longer fit makes
    iterate(again, on_iteration=checkpoint.committer(tmp_path, "k", {}, again, resumed))
    whole = start_fit(Y, V, longer)
    iterate(whole)
    assert np.array_equal(again.order, whole.order) and np.array_equal(again.weights, whole.weights)
    assert len(checkpoint.load(tmp_path, "k")[1]) == len(whole.history)


def test_a_second_writer_of_a_checkpoint_stops_at_once(tmp_path):
    folder = tmp_path / "fit.checkpoint"
    with checkpoint.locked(folder):
        with pytest.raises(InputError, match="another fit is writing this checkpoint"):
            with checkpoint.locked(folder):
                pass
    with checkpoint.locked(folder):  # free again once the first is done
        pass
