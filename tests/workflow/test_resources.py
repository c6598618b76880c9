"""Stage resources: the cache budget is the tightest of config, job and machine; the numpy device."""

import logging

from posefix.workflow.resources import available_memory, cache_budget, opencl_device


def test_cache_budget_is_the_tightest_limit(caplog):
    gb = 1e9
    assert cache_budget(8 * gb, None, 1 * gb, available=100 * gb) == 8 * gb          # the config
    assert cache_budget(8 * gb, 5000, 1 * gb, available=100 * gb) == 4 * gb          # the job's mem_mb less the rest
    with caplog.at_level(logging.WARNING):
        assert cache_budget(8 * gb, None, 1 * gb, available=5 * gb) == 3 * gb       # 80 % of the machine less the rest
    assert "only 5.0 GB available" in caplog.text
    assert cache_budget(8 * gb, 500, 1 * gb, available=100 * gb) == 0.0            # nothing left: no cache


def test_available_memory_is_positive():
    assert available_memory() > 0


def test_numpy_device_is_no_device():
    assert opencl_device("numpy", 1) == (None, "numpy (CPU)")
