"""`make bench`: run the pipeline on the benchmark libraries and collect the benchmarks under reports/bench/.

Libraries: lion, cat and horse poses from ../shared/data (the demo library when that folder is
absent, which the report says). Benchmarks so far: the self-intersection detector against
pymeshlab (benchmarks/detector.py) on every key frame, the RBF fit variants with the scipy peer
check (benchmarks/fit.py), and the OpenCL integration against numpy on the lion poses
(benchmarks/integrate.py).
"""

import argparse
import os
import platform
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("POSEFIX_DATA", ROOT.parent / "shared" / "data"))
LIBRARIES = ("lion-poses", "cat-poses", "horse-poses")
PAPER = ("S0 Table 1 (GTX 460 + 4-core Phenom II, averages over poses): lion 2.7k centres, kappa 2e6, 13 s; "
         "cat 4.5k, 2e7, 42 s; horse 4.6k, 7e6, 43 s (worst-m selection of Carr et al.: 12-15k centres, "
         "kappa 1e10-1e11). S0 reached its eps = 1e-4 d; our fits stop at max_centers (see the stop column).\n\n")


def machine():
    """One line about this machine: CPU model and core count."""
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} cores, Python {platform.python_version()}"


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--cores", type=int, default=2)
    parser.add_argument("--out", default=str(ROOT / "reports" / "bench"))
    args = parser.parse_args()
    libraries = [DATA / name for name in LIBRARIES if (DATA / name).is_dir()]
    note = "" if libraries else f"\n{DATA} is absent: ran on the built-in demo library.\n"
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    detector, fit, integrate = [], [], []
    for lib in libraries or [None]:
        config = ["--config", f"library={lib}"] if lib else []
        subprocess.run([sys.executable, "-m", "snakemake", "--cores", str(args.cores), *config],
                       cwd=ROOT, check=True)
        name = lib.name if lib else "demo"
        results = str(ROOT / "results" / name)
        subprocess.run([sys.executable, str(ROOT / "benchmarks" / "detector.py"),
                        "--results", results, "--out", str(out / f"detector-{name}")], check=True)
        detector.append((out / f"detector-{name}.md").read_text())
        subprocess.run([sys.executable, str(ROOT / "benchmarks" / "fit.py"), "--library", name,
                        "--results", results, "--out", str(out / f"fit-{name}")], check=True, cwd=ROOT)
        fit.append((out / f"fit-{name}.md").read_text())
        if name in ("lion-poses", "demo"):
            subprocess.run([sys.executable, str(ROOT / "benchmarks" / "integrate.py"), "--library", name,
                            "--results", results, "--out", str(out / f"integrate-{name}")], check=True, cwd=ROOT)
            integrate.append((out / f"integrate-{name}.md").read_text())
    header = f"Machine: {machine()}.\n{note}\nCommand: `make bench` (benchmarks/run.py).\n\n"
    (out / "detector.md").write_text("# Self-intersection detector: posefix vs pymeshlab\n\n" + header
                                     + "\n".join(detector))
    (out / "fit.md").write_text("# RBF fit: S0 Table 1 on our machine\n\n" + header + PAPER + "\n".join(fit))
    (out / "integrate.md").write_text("# Integration: OpenCL vs numpy\n\n" + header + "\n".join(integrate))
    print(f"wrote {out / 'detector.md'}, {out / 'fit.md'} and {out / 'integrate.md'}")


if __name__ == "__main__":
    main()
