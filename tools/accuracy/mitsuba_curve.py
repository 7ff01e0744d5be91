#!/usr/bin/env python3
"""Mitsuba 3's path tracer's error against time on one scene, as a CSV `caustic study --compare`
reads (point, seed, cpu_s, wall_s, rel_rmse, block_bias), and the two references a study needs.

    tools/validate/.venv/bin/python tools/accuracy/mitsuba_curve.py SCENE.lua OUT_DIR \
        [--scale F] [--region x0,y0,x1,y1] [--spp 4,16,64,256] [--ref-spp 4096] [--refs DIR]

References: REFS/NAME.exr and NAME.second.exr (two independent Mitsuba renders at --ref-spp),
rendered here when missing (tools/validate/refs holds the validation scenes' ones). Errors are
against the truth as estimated from both (tools/validate/run.py's cross estimator), so the
references' noise drops out; CPU time is the process's (Mitsuba's LLVM threads included), the
first render's JIT compilation excluded by a warm-up render.
"""

import argparse
import os
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "validate"))
import run as validate  # noqa: E402  (tools/validate/run.py: loading, rendering, metrics)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--scale", type=float, default=1.0)
    ap.add_argument("--region", help="x0,y0,x1,y1 in pixels (end exclusive), as caustic study's")
    ap.add_argument("--spp", default="4,16,64,256")
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--refs", default=os.path.join(validate.ROOT, "tools", "validate", "refs"))
    ap.add_argument("--caustic", default=os.path.join(validate.ROOT, "target", "release", "caustic"))
    a = ap.parse_args()
    validate.choose_variant()
    name = os.path.splitext(os.path.basename(a.scene))[0]
    os.makedirs(a.out, exist_ok=True)
    os.makedirs(a.refs, exist_ok=True)
    xml = os.path.join(a.out, name + ".xml")
    subprocess.run([a.caustic, "export-mitsuba", a.scene, "-o", xml, "--scale", str(a.scale)],
                   check=True, stderr=subprocess.DEVNULL)
    ref, second = (os.path.join(a.refs, name + s) for s in (".exr", ".second.exr"))
    if not (os.path.exists(ref) and os.path.exists(second)):
        validate.render_mitsuba(xml, a.ref_spp, 1, ref)
        validate.render_mitsuba(xml, a.ref_spp, 2, second)
    r1, r2 = validate.load(ref), validate.load(second)
    h, w, _ = r1.shape
    box = (0, 0, 1, 1)
    if a.region:
        x0, y0, x1, y1 = (int(v) for v in a.region.split(","))
        box = (x0 / w, y0 / h, x1 / w, y1 / h)
    validate.render_mitsuba(xml, 1, 99, os.path.join(a.out, "warmup.exr"))
    rows = ["point,seed,setting,cpu_s,wall_s,rel_rmse,block_bias"]
    for i, spp in enumerate(int(s) for s in a.spp.split(",")):
        out = os.path.join(a.out, f"mitsuba_{spp}spp.exr")
        cpu, wall = validate.render_mitsuba(xml, spp, 11 + i, out)
        m = validate.metrics(validate.load(out), r1, r2, box)
        rows.append(f"{i},0,\"spp={spp}\",{cpu:.4f},{wall:.4f},{m['rel_rmse']:.6f},{m['block_bias']:.6f}")
        print(f"mitsuba {name} {spp} spp: {cpu:.2f} s CPU, relative RMSE {m['rel_rmse']:.4f}",
              file=sys.stderr)
    with open(os.path.join(a.out, "mitsuba.csv"), "w") as f:
        f.write("\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
