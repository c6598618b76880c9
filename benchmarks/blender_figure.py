"""docs/blender-shape-key.png: a shape key of the demo limb and the key that *Repair shape keys* wrote, rendered
headless by bpy (Cycles on the CPU), intersecting faces red, in 128 colours. Needs the bpy environment (``make test`` makes
``.venv-blender``); runs the add-on as its tests do (tests/blender/scene.py).

    .venv/bin/python benchmarks/blender_figure.py [--pose demo-03] [--out docs/blender-shape-key.png]
"""

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

from posefix.mesh.intersections import intersecting_faces, self_intersecting_pairs
from posefix.workflow.blender_addon import build_addon
from posefix.workflow.demo import demo_library

ROOT = Path(__file__).resolve().parents[1]
BLENDER_PYTHON = Path(os.environ.get("POSEFIX_BLENDER_PYTHON", ROOT / ".venv-blender" / "bin" / "python"))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pose", default="demo-03")
    parser.add_argument("--out", default=str(ROOT / "docs" / "blender-shape-key.png"))
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="posefix-blender-figure-"))
    V, F, poses = demo_library(around=24)
    f32 = lambda a: a.astype(np.float32).astype(np.float64)  # noqa: E731 (Blender's float32)
    np.savez(work / "limb.npz", reference=f32(V), faces=F, poses=np.stack([f32(p) for p in poses.values()]),
             names=np.array(list(poses)))
    env = dict(os.environ, HOME=str(work / "home"))
    subprocess.run([BLENDER_PYTHON, ROOT / "tests" / "blender" / "scene.py", "new", work / "limb.npz", work / "new",
                    build_addon(work), sys.executable], check=True, env=env, capture_output=True)
    keys = np.load(work / "new.npz")
    left, right = (keys[name].astype(np.float64) for name in (args.pose, f"{args.pose}.repaired"))
    hit = lambda X: intersecting_faces(self_intersecting_pairs(X, F), len(F))  # noqa: E731
    np.savez(work / "shapes.npz", faces=F, left=left, right=right, left_hit=hit(left), right_hit=hit(right))
    print(f"{args.pose}: {hit(left).sum()} intersecting faces; {args.pose}.repaired: {hit(right).sum()}")
    subprocess.run([BLENDER_PYTHON, ROOT / "benchmarks" / "blender_render.py", work / "shapes.npz", args.out],
                   check=True, env=env, capture_output=True)
    Image.open(args.out).convert("RGB").quantize(128, dither=Image.Dither.NONE).save(args.out, optimize=True)
    print(args.out)


if __name__ == "__main__":
    main()
