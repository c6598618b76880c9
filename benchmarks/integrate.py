"""Integration benchmark: the OpenCL kernel against the numpy backend on the same fields.

For every pose of a library (``results/<library>/<pose>/fit.h5``, from the pipeline) the OpenCL
backend, and on the first ``--numpy-poses`` poses the numpy backend too, integrate every reference
vertex with the pipeline's tolerances; reported: seconds, ratio, the
largest difference of the end positions, and RBF kernel evaluations per second. One kernel
evaluation (distance, the hand-written log, weighted sum) is about 50 floating-point operations
(a fused multiply-add counted as 2). The device's double-precision peak is measured, not taken
from a data sheet: an OpenCL kernel of independent fused multiply-adds on 8-wide double vectors,
on the same device and queue settings (a listed-clock estimate, cores x clock x 16, is printed
next to it; turbo clocks and extra add pipes make it a poor bound).

    python benchmarks/integrate.py --library lion-poses --out reports/bench/integrate-lion-poses
"""

import argparse
import json
import os
import time
from pathlib import Path

import posefix  # noqa: F401  (runtime defaults before numpy)
import h5py
import numpy as np
import yaml
from threadpoolctl import threadpool_limits

from posefix.spacetime.integration import field_velocity, rk45
from posefix.spacetime.integration_opencl import rk45_opencl, select_device
from posefix.spacetime.rbf import RBFField

FLOPS_PER_EVALUATION = 50


FMA_KERNEL = """
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
__kernel void fma_peak(__global double *out, const int iters) {
    double8 a0 = (double8)(get_global_id(0)), a1 = a0 + 1.0, a2 = a0 + 2.0, a3 = a0 + 3.0;
    double8 a4 = a0 + 4.0, a5 = a0 + 5.0, a6 = a0 + 6.0, a7 = a0 + 7.0;
    const double8 b = (double8)(0.999999), c = (double8)(1e-7);
    for (int i = 0; i < iters; ++i) {
        a0 = fma(a0, b, c); a1 = fma(a1, b, c); a2 = fma(a2, b, c); a3 = fma(a3, b, c);
        a4 = fma(a4, b, c); a5 = fma(a5, b, c); a6 = fma(a6, b, c); a7 = fma(a7, b, c);
    }
    double8 s = a0 + a1 + a2 + a3 + a4 + a5 + a6 + a7;
    out[get_global_id(0)] = s.s0 + s.s1 + s.s2 + s.s3 + s.s4 + s.s5 + s.s6 + s.s7;
}
"""


def measured_peak_gflops(device, items=4096, iters=20000):
    """Double-precision GFLOP/s of an FMA-only OpenCL kernel on ``device`` (best of 3 runs)."""
    import pyopencl as cl
    ctx = cl.Context([device])
    queue = cl.CommandQueue(ctx)
    kernel = cl.Program(ctx, FMA_KERNEL).build().fma_peak
    out = cl.Buffer(ctx, cl.mem_flags.WRITE_ONLY, 8 * items)
    kernel(queue, (items,), None, out, np.int32(10)).wait()  # warm-up
    best = np.inf
    for _ in range(3):
        start = time.perf_counter()
        kernel(queue, (items,), None, out, np.int32(iters)).wait()
        best = min(best, time.perf_counter() - start)
    return items * iters * 8 * 8 * 2 / best / 1e9


def peak_gflops():
    """Listed-clock estimate: cores x clock x 16 (AVX-512 FMA) from /proc/cpuinfo, in GFLOP/s."""
    mhz = [float(line.split(":")[1]) for line in Path("/proc/cpuinfo").read_text().splitlines()
           if line.startswith("cpu MHz")]
    return os.cpu_count() * (max(mhz) if mhz else 2500.0) / 1000.0 * 16


def load(folder):
    with h5py.File(folder / "fit.h5", "r") as fh:
        field = RBFField(fh["centers"][()], fh["weights"][()], fh["poly"][()], fh["shift"][()], float(fh["scale"][()]))
    with h5py.File(folder / "constraints.h5", "r") as fh:
        tau, d, s = (float(fh["metrics"].attrs[k]) for k in ("tau", "bbox_diagonal", "samples"))
    with h5py.File(folder / "keyframes.h5", "r") as fh:
        X0 = fh["reference"][()]
    return field, tau, d, np.arange(int(s) + 1) / s, X0


def evaluations(steps, rejected, centers):
    """Kernel evaluations of a Dormand-Prince run: 6 new stages per attempted step plus the first."""
    return float((6 * (steps + rejected) + 1).sum() * centers)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--library", required=True)
    parser.add_argument("--results", default=None)
    parser.add_argument("--out", required=True)
    parser.add_argument("--config", default="config.yaml")
    parser.add_argument("--numpy-poses", type=int, default=3, help="poses on which the (slow) numpy peer runs too")
    args = parser.parse_args()
    cfg = yaml.safe_load(Path(args.config).read_text())["integrate"]
    device, name = select_device("auto")
    if device is None:
        print(f"no OpenCL device ({name}): nothing to compare")
        return
    rows = []
    for i, folder in enumerate(sorted(Path(args.results or f"results/{args.library}").glob("*/fit.h5"))):
        field, tau, d, times, X0 = load(folder.parent)
        start = time.perf_counter()
        a = rk45_opencl(device, field, tau, X0, times, cfg["rtol"], cfg["atol_rel"] * d, cfg["h0"])
        cl_s = time.perf_counter() - start
        n_eval = evaluations(a[2], a[3], len(field.weights))
        rows.append({"pose": folder.parent.name, "vertices": len(X0), "centers": len(field.weights),
                     "opencl_seconds": cl_s, "numpy_seconds": None, "speedup": None, "max_difference_rel": None,
                     "evaluations": n_eval, "evaluations_per_second": n_eval / cl_s,
                     "steps_mean": float(a[2].mean())})
        if i < args.numpy_poses:
            with threadpool_limits(2):
                start = time.perf_counter()
                b = rk45(field_velocity(field, tau), X0, atol=cfg["atol_rel"] * d, rtol=cfg["rtol"], h0=cfg["h0"],
                         sample_times=times)
                np_s = time.perf_counter() - start
            rows[-1].update(numpy_seconds=np_s, speedup=np_s / cl_s,
                            max_difference_rel=float(np.abs(a[0] - b[0]).max() / d))
        print(json.dumps(rows[-1]), flush=True)
    peak, listed = measured_peak_gflops(device), peak_gflops()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps({"device": name, "peak_gflops_measured": peak,
                                                        "peak_gflops_listed_clock": listed, "rows": rows}, indent=1))
    lines = [f"### Integration: {args.library}", "",
             f"OpenCL device: {name}; numpy backend with 2 BLAS threads (on the first {args.numpy_poses} poses); "
             f"rtol {cfg['rtol']}, atol {cfg['atol_rel']} d.", "",
             "| pose | vertices | centres | steps | OpenCL s | numpy s | numpy / OpenCL | max diff / d | 1e9 evaluations/s | GFLOP/s (x50) |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        peer = (f"{r['numpy_seconds']:.1f} | {r['speedup']:.1f} | {r['max_difference_rel']:.1e}"
                if r["numpy_seconds"] is not None else "- | - | -")
        lines.append(f"| {r['pose']} | {r['vertices']} | {r['centers']} | {r['steps_mean']:.1f} | {r['opencl_seconds']:.2f} | "
                     f"{peer} | {r['evaluations_per_second'] / 1e9:.2f} | "
                     f"{r['evaluations_per_second'] * FLOPS_PER_EVALUATION / 1e9:.0f} |")
    mean_rate = np.mean([r["evaluations_per_second"] for r in rows])
    lines += ["", f"Mean {mean_rate / 1e9:.2f}e9 kernel evaluations/s, about {mean_rate * FLOPS_PER_EVALUATION / 1e9:.0f} "
              f"GFLOP/s at ~{FLOPS_PER_EVALUATION} flops each (a fused multiply-add counted as 2): "
              f"{100 * mean_rate * FLOPS_PER_EVALUATION / 1e9 / peak:.0f} % of the device's measured FMA peak of "
              f"{peak:.0f} GFLOP/s (an OpenCL kernel of independent double8 FMAs; cores x listed clock x 16 would "
              f"say {listed:.0f}). S0: 19-39 s per pose on a GTX 460."]
    out.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
