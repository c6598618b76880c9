"""`make bench`: run the pipeline on the benchmark libraries and collect the benchmarks under reports/bench/.

Libraries: lion, cat and horse poses from ../shared/data (the demo library when that folder is
absent, which the report says). Benchmarks so far: the self-intersection detector against
pymeshlab (benchmarks/detector.py) on every key frame.
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
    sections = []
    for lib in libraries or [None]:
        config = ["--config", f"library={lib}"] if lib else []
        subprocess.run([sys.executable, "-m", "snakemake", "--cores", str(args.cores), *config],
                       cwd=ROOT, check=True)
        name = lib.name if lib else "demo"
        subprocess.run([sys.executable, str(ROOT / "benchmarks" / "detector.py"),
                        "--results", str(ROOT / "results" / name), "--out", str(out / f"detector-{name}")],
                       check=True)
        sections.append((out / f"detector-{name}.md").read_text())
    text = (f"# Self-intersection detector: posefix vs pymeshlab\n\nMachine: {machine()}.\n{note}\n"
            "Command: `make bench` (benchmarks/run.py, benchmarks/detector.py).\n\n" + "\n".join(sections))
    (out / "detector.md").write_text(text)
    print(f"wrote {out / 'detector.md'}")


if __name__ == "__main__":
    main()
