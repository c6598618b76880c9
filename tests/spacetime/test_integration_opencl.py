"""The OpenCL kernels: RK45 and field values agree with numpy; the hand-written log is accurate."""

import numpy as np
import pytest

from conftest import smooth_field_problem
from posefix.spacetime.fit import FitSettings, iterate, start_fit
from posefix.spacetime.integration import field_velocity, rk45
from posefix.spacetime.integration_opencl import KERNEL, FieldEvaluator, OpenCLIntegrator, rk45_opencl, select_device
from posefix.spacetime.rbf import kernel_matrix, poly_basis


def _device():
    device, why = select_device("auto")
    if device is None:
        pytest.skip(f"OpenCL not available here ({why}); the numpy backend is tested on its own")
    return device


def _rbf_field(seed=0):
    rng = np.random.default_rng(seed)
    Y = rng.uniform(0, 1, size=(1200, 4))
    V = 0.3 * np.stack([np.sin(Y @ [1.0, 0.5, 0.3, 0.2]), np.cos(Y @ [0.2, 0.7, 0.4, 0.1]),
                        0.2 * (Y ** 3).sum(1)], 1)
    fit = start_fit(Y, V, FitSettings(eps=1e-5, max_centers=500, batch=64))
    iterate(fit)
    return fit.field()


def test_opencl_and_numpy_agree_on_an_rbf_field():
    device = _device()
    field = _rbf_field()
    X0 = np.random.default_rng(2).uniform(0, 1, size=(300, 3))
    times = np.linspace(0, 1, 7)
    a = rk45(field_velocity(field, 1.0), X0, rtol=1e-11, atol=1e-11, sample_times=times)
    b = rk45_opencl(device, field, 1.0, X0, times, 1e-11, 1e-11)
    d = np.linalg.norm(X0.max(0) - X0.min(0))
    assert np.abs(a[0] - b[0]).max() <= 1e-8 * d
    assert np.abs(a[1] - b[1]).max() <= 1e-8 * d
    # with the default tolerances both take the same steps on this field
    a = rk45(field_velocity(field, 1.0), X0, rtol=1e-9, atol=1e-7, sample_times=times)
    b = OpenCLIntegrator(device, vec=4).integrate(field, 1.0, X0, times, 1e-9, 1e-7)
    assert np.abs(a[0] - b[0]).max() <= 1e-8 * d


def test_opencl_fast_log_is_accurate():
    import pyopencl as cl
    device = _device()
    ctx = cl.Context([device])
    queue = cl.CommandQueue(ctx)
    source = KERNEL + r"""
    __kernel void logs(__global const double *x, __global double *y) {
        const int i = get_global_id(0);
        VD v = (VD)(x[i]);
        VD r = fast_log(v);
        y[i] = ((double *)&r)[0];
    }"""
    program = cl.Program(ctx, source).build(options=["-DVEC=2"])
    x = np.concatenate([np.logspace(-300, 300, 5000), np.random.default_rng(3).uniform(0.5, 2.0, 5000)])
    y = np.empty_like(x)
    mf = cl.mem_flags
    bx = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=x)
    by = cl.Buffer(ctx, mf.WRITE_ONLY, y.nbytes)
    program.logs(queue, (len(x),), None, bx, by)
    cl.enqueue_copy(queue, y, by)
    exact = np.log(x)
    rel = np.abs(y - exact) / np.maximum(np.abs(exact), 1e-300)
    big = np.abs(exact) > 1e-3  # relative error of log near 1 is measured absolutely below
    assert rel[big].max() <= 1e-15 and np.abs(y - exact)[~big].max() <= 1e-17


@pytest.mark.parametrize("vec", [None, 4])
def test_field_values_agree_with_numpy(vec):
    device = _device()
    rng = np.random.default_rng(4)
    Z = rng.uniform(-1.5, 1.5, size=(3001, 4))   # not a multiple of any work-group or vector width
    C, w, p = Z[rng.choice(3001, 333, replace=False)], rng.normal(size=(333, 3)), rng.normal(size=(15, 3))
    expected = kernel_matrix(Z, C) @ w + poly_basis(Z) @ p
    evaluator = FieldEvaluator(device, Z, vec=vec)
    got = evaluator(C, w, p)
    assert np.abs(got - expected).max() <= 1e-10 * np.abs(expected).max()
    assert np.array_equal(evaluator(C[:20], w[:20], p), evaluator(C[:20], w[:20], p))  # deterministic, reusable


def test_fit_without_the_cache_matches_the_cached_fit():
    """The residual recomputed on the device (or in numpy) selects the same centres as the cached one."""
    device = _device()
    Y, V = smooth_field_problem()
    settings = dict(eps=0.0, max_centers=400, batch=64, candidates=256)
    fits = {}
    for name, budget, dev in (("cached", 8e9, None), ("opencl", 0.0, device), ("numpy", 0.0, None)):
        fits[name] = start_fit(Y, V, FitSettings(**settings, memory_bytes=budget), dev)
        iterate(fits[name])
        assert fits[name].evaluator.mode == name
    scale = np.abs(fits["cached"].residual).max()
    for name in ("opencl", "numpy"):
        assert np.array_equal(fits[name].order, fits["cached"].order)
        assert np.abs(fits[name].residual - fits["cached"].residual).max() <= 1e-10 * scale
