#!/usr/bin/env python3
"""Local radii against one radius per map for the progressive integrator, on validation scenes
with caustics and dim regions: each region's relative RMSE against the two Mitsuba 3
references after 16 and 64 passes, mean over seeds, and its slope against passes (progressive
photon mapping predicts -1/3 for the maps' part, -1/2 for the Monte Carlo terms).

    cargo build --release && python3 tools/accuracy/local_radii.py > docs/accuracy/local_radii.md

Standard library only. About 12 minutes on 2 cores (the renders' times are in the table)."""

import math
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "validate"))
from regions import pixels, regions  # noqa: E402

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
BIN = os.path.join(ROOT, "target", "release", "caustic")
OUT = os.path.join(ROOT, "target", "accuracy", "local_radii")
REFS = os.path.join(ROOT, "tools", "validate", "refs")
PASSES = (16, 64)
SEEDS = (0, 1)
# (scene, extra flags, what the case shows)
CASES = [
    ("cornell_glass", [], "glass ball's caustic; indirect light by final gathering"),
    ("glass_in_water", [], "caustic focused through water and glass"),
    ("cornell_diffuse", ["--indirect", "direct"],
     "no caustic; the global map read directly at every visible point (dim ceiling)"),
]


def render(scene, flags, mode, passes, seed):
    """Renders one case; returns (image path, seconds the render reported)."""
    os.makedirs(OUT, exist_ok=True)
    out = os.path.join(OUT, f"{scene}.{mode}.{passes}.{seed}.exr")
    cmd = [BIN, "render", os.path.join(ROOT, "scenes", "validate", scene + ".lua"), "-o", out,
           "--integrator", "progressive", "--passes", str(passes), "--local-radii", mode,
           "--seed", str(seed), "-q", "--stats"] + flags
    text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    secs = float(re.search(r"progressive: \d+ passes in ([\d.]+) s", text).group(1))
    return out, secs


def rel_rmse(image, scene, window):
    """Returns the relative RMSE of `image` in pixel `window` against the scene's references."""
    ref = os.path.join(REFS, scene + ".exr")
    second = os.path.join(REFS, scene + ".second.exr")
    box = ",".join(str(v) for v in window)
    text = subprocess.run([BIN, "diff", image, ref, "--second", second, "--region", box],
                          check=True, capture_output=True, text=True).stdout
    return float(re.search(r"relative RMSE ([\d.e+-]+)", text).group(1))


def main():
    print("# Local radii against one radius per map (progressive integrator)\n")
    print("Made by `python3 tools/accuracy/local_radii.py` (relative RMSE against the two "
          "Mitsuba 3 references of `tools/validate`, mean of "
          f"{len(SEEDS)} seeds; slope of log error against log passes between "
          f"{PASSES[0]} and {PASSES[1]} passes).\n")
    for scene, flags, what in CASES:
        size = 96
        regs = [(name, pixels(box, size, size)) for name, box in
                regions(os.path.join(ROOT, "scenes", "validate", scene + ".lua"))]
        err = {}
        secs = {}
        for mode in ("off", "on"):
            for passes in PASSES:
                for seed in SEEDS:
                    image, s = render(scene, flags, mode, passes, seed)
                    secs[mode, passes] = secs.get((mode, passes), 0.0) + s / len(SEEDS)
                    for name, window in regs:
                        e = rel_rmse(image, scene, window)
                        key = (mode, passes, name)
                        err[key] = err.get(key, 0.0) + e / len(SEEDS)
        flag_text = " ".join(flags) or "defaults"
        print(f"## {scene} ({flag_text}): {what}\n")
        print("| region | radii | " + " | ".join(f"{p} passes" for p in PASSES)
              + " | slope | local / one |")
        print("|---|---|" + "---|" * len(PASSES) + "---|---|")
        for name, _ in regs:
            for mode, label in (("off", "one per map"), ("on", "local")):
                es = [err[mode, p, name] for p in PASSES]
                slope = math.log(es[-1] / es[0]) / math.log(PASSES[-1] / PASSES[0])
                ratio = (f"{err['on', PASSES[-1], name] / err['off', PASSES[-1], name]:.2f}"
                         if mode == "on" else "")
                print(f"| {name} | {label} | " + " | ".join(f"{e:.4f}" for e in es)
                      + f" | {slope:.2f} | {ratio} |")
        times = ", ".join(f"{m} {secs[m, p]:.1f} s" for p in PASSES for m in ("off", "on")
                          if True)
        print(f"\nRender time (wall, 2 cores), {PASSES[0]} then {PASSES[-1]} passes: {times}.\n")


if __name__ == "__main__":
    main()
