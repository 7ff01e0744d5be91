#!/usr/bin/env python3
"""Validates caustic against Mitsuba 3's path tracer on the scenes in scenes/validate/.

    bash tools/validate/setup.sh                       # once: Mitsuba 3 in tools/validate/.venv
    tools/validate/.venv/bin/python tools/validate/run.py [--render-refs] [--ref-spp 4096]

For each scene: `caustic export-mitsuba` writes the Mitsuba scene; the reference is
tools/validate/refs/NAME.exr (rendered with --render-refs, together with a second, independent
reference at the same sample count whose distance to the first states the references' noise
floor: NAME.second.exr); caustic renders the scene at its defaults; the metrics per region go
to docs/validation.md and the pictures (reference | caustic | difference) to docs/validation/.
With --equal-time, Mitsuba also renders at caustic's CPU time and both errors are compared.

With --gltf, the scenes are glTF files rendered as whole scenes instead (by default
scenes/gltf/{copper_bowl,frosted_sphere,glass_of_water,textured_box}.glb, or --scenes), at --scale 0.25
(200x150) for both the export and caustic's render (with the full-size render's photon counts,
--photon-scale 16, and its samples per image area, --spp 64, unless --caustic-args sets them),
with their regions from
scenes/validate/gltf_regions.txt (lines `SCENE REGION x0 y0 x1 y1`), and the table goes to
docs/validation/gltf.md (a section to merge into docs/validation.md, which is left alone):

    tools/validate/.venv/bin/python tools/validate/run.py --gltf [--render-refs]

Regions come from the scene's `-- region NAME x0 y0 x1 y1` comments (fractions of the image).
Metrics per region, over all three channels, against the truth as estimated from the two
references (see cross_rms: the references' noise drops out): the mean ratio, RMSE, relative
RMSE, the block error (the same over the region's 8x8-pixel block means) and, with --seeds 2,
the bias (the block error between two caustic seeds and the two references: caustic's own
noise drops out too).
CI does not run this (it needs Mitsuba); the committed references let anyone rerun the caustic
side without rendering them again.
"""

import argparse
import glob
import json
import os
import subprocess
import sys
import tempfile
import time

import mitsuba as mi
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from regions import pixels, regions  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
REFS = os.path.join(ROOT, "tools", "validate", "refs")
PICS = os.path.join(ROOT, "docs", "validation")


def choose_variant():
    for v in ("llvm_ad_rgb", "scalar_rgb"):
        try:
            mi.set_variant(v)
            return v
        except (ImportError, AttributeError, RuntimeError):
            continue
    sys.exit("validate: no usable Mitsuba variant")


GLTF_SCENES = [os.path.join(ROOT, "scenes", "gltf", n + ".glb")
               for n in ("copper_bowl", "frosted_sphere", "glass_of_water", "textured_box")]
GLTF_REGIONS = os.path.join(ROOT, "scenes", "validate", "gltf_regions.txt")


def sidecar_regions(path, name):
    """The regions of scene NAME in a sidecar file of lines `SCENE REGION x0 y0 x1 y1 [ptracer]`
    (fractions of the image; `#` starts a comment), in file order. `ptracer` marks a region of
    diffuse surfaces seen directly that a point light reaches through glass: a path tracer
    cannot sample that light (it would have to hit the point), so the region is compared with
    Mitsuba's particle tracer, which traces from the lights and is complete on such surfaces."""
    out = []
    for line in open(path):
        f = line.split("#", 1)[0].split()
        if len(f) in (6, 7) and f[0] == name and (len(f) == 6 or f[6] == "ptracer"):
            out.append((f[1] + (" (ptracer)" if len(f) == 7 else ""),
                        tuple(float(v) for v in f[2:6])))
        elif f and (len(f) not in (6, 7) or (len(f) == 7 and f[6] != "ptracer")):
            sys.exit(f"validate: {path}: expected SCENE REGION x0 y0 x1 y1 [ptracer], got {line.strip()!r}")
    return out


def load(path):
    return np.array(mi.Bitmap(path), dtype=np.float64)[..., :3]


def render_mitsuba(xml, spp, seed, out):
    scene = mi.load_file(xml)
    start = time.process_time()
    wall = time.time()
    img = mi.render(scene, spp=spp, seed=seed)
    mi.Bitmap(img).write(out)
    return time.process_time() - start, time.time() - wall


def crop(img, box):
    h, w, _ = img.shape
    return pixels(box, w, h)


def block_means(img, box):
    """The means of the 8x8-pixel blocks (aligned to the image) that lie inside the region."""
    x0, y0, x1, y1 = crop(img, box)
    out = []
    for by in range(y0 - y0 % 8, y1, 8):
        for bx in range(x0 - x0 % 8, x1, 8):
            if by >= y0 and bx >= x0 and by + 8 <= y1 and bx + 8 <= x1:
                out.append(img[by:by + 8, bx:bx + 8].mean())
    return np.array(out)


def cross_rms(a1, b1, a2, b2):
    """sqrt(max(0, mean((a1 - b1) * (a2 - b2)))): with the pairs' errors independent, the
    expected product is the squared difference of their expectations, so the noise of whichever
    side is doubled (two references, or two seeds) drops out instead of adding to the error."""
    return float(np.sqrt(max(0.0, float(np.mean((a1 - b1) * (a2 - b2))))))


def metrics(c, r1, r2, box, c2=None):
    """The metrics of caustic's image c against the truth, estimated from two independent
    references r1 and r2 (see cross_rms), over the region box; with c2 (a render with another
    seed) also the seed-pair block bias, from which caustic's own noise drops out too."""
    x0, y0, x1, y1 = crop(r1, box)
    cr, a, b = (img[y0:y1, x0:x1] for img in (c, r1, r2))
    mean = 0.5 * (a.mean() + b.mean())
    rmse = cross_rms(cr, a, cr, b)
    cb, ab, bb = (block_means(img, box) for img in (c, r1, r2))
    bias = cross_rms(cb, ab, cb, bb) / mean if len(cb) else float("nan")
    out = {"mean_ratio": float(cr.mean() / mean), "rmse": rmse, "rel_rmse": rmse / mean,
           "block_bias": bias, "ref_mean": float(mean)}
    if c2 is not None:
        out["seed_bias"] = cross_rms(cb, ab, block_means(c2, box), bb) / mean if len(cb) else float("nan")
    return out


def ref_noise(r1, r2, box):
    """One reference's own relative RMSE and block error: the two references' distance over sqrt 2."""
    x0, y0, x1, y1 = crop(r1, box)
    a, b = r1[y0:y1, x0:x1], r2[y0:y1, x0:x1]
    mean = 0.5 * (a.mean() + b.mean())
    ab, bb = block_means(r1, box), block_means(r2, box)
    rel = float(np.sqrt(np.mean((a - b) ** 2) / 2)) / mean
    blk = float(np.sqrt(np.mean((ab - bb) ** 2) / 2)) / mean if len(ab) else float("nan")
    return {"rel_rmse": rel, "block_bias": blk}


def tonemap(x, scale):
    return (np.clip(x / scale, 0, 1) ** (1 / 2.2) * 255).astype(np.uint8)


def picture(c, r, path):
    scale = max(np.percentile(r, 99), 1e-9)
    diff = np.abs(c - r).mean(axis=2)
    # False colour: red where caustic is brighter, blue where darker, at 4x the contrast.
    signed = (c - r).mean(axis=2) / scale * 4
    false = np.zeros_like(c)
    false[..., 0] = np.clip(signed, 0, 1)
    false[..., 2] = np.clip(-signed, 0, 1)
    false[..., 1] = np.clip(diff / scale * 4, 0, 1) * 0.2
    row = np.concatenate([tonemap(r, scale), tonemap(c, scale), (false * 255).astype(np.uint8)], axis=1)
    mi.Bitmap(row).write(path)


def caustic_render(binary, scene, out, args):
    cmd = [binary, "render", scene, "-q", "-o", out] + args
    start = time.time()
    ru = os.times()
    subprocess.run(cmd, check=True, cwd=ROOT)
    ru2 = os.times()
    return ru2.children_user - ru.children_user + ru2.children_system - ru.children_system, time.time() - start


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--render-refs", action="store_true", help="render the Mitsuba references anew")
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--caustic", default=os.path.join(ROOT, "target", "release", "caustic"))
    ap.add_argument("--scenes", help="a glob of the scenes (default: scenes/validate/*.lua; "
                    "with --gltf, the three glTF scenes named above)")
    ap.add_argument("--gltf", action="store_true", help="validate glTF scenes (see the top)")
    ap.add_argument("--regions", help="a sidecar file of lines `SCENE REGION x0 y0 x1 y1` "
                    "(default with --gltf: scenes/validate/gltf_regions.txt; else the scene's "
                    "`-- region` comments)")
    ap.add_argument("--scale", type=float, help="export and render at this multiple of the "
                    "scene's image size (default: 1; with --gltf 0.25)")
    ap.add_argument("--render-with", help="the caustic binary that renders (default: --caustic), "
                    "e.g. an older build for a before/after table")
    ap.add_argument("--equal-time", action="store_true", help="also compare at equal CPU time")
    ap.add_argument("--caustic-args", default="", help="extra caustic render arguments")
    ap.add_argument("--label", default="caustic defaults")
    ap.add_argument("--seeds", type=int, default=2, choices=(1, 2),
                    help="2: also render with --seed 1 for the seed-pair bias column")
    ap.add_argument("--out", help="the Markdown file to write (default: docs/validation.md; "
                    "with --gltf docs/validation/gltf.md)")
    a = ap.parse_args()
    if a.gltf:
        scenes = sorted(glob.glob(a.scenes)) if a.scenes else GLTF_SCENES
        a.regions = a.regions or GLTF_REGIONS
        a.scale = 0.25 if a.scale is None else a.scale
        # The scenes render at a quarter of their size only so that 4096-spp references take
        # minutes; the photon counts are those of the full-size render a user gets at the
        # defaults (a --scale preview traces fewer, a preview's convenience, not what is
        # validated): a photon map's bias is set by the photons' density on the surfaces, which
        # the image size does not change.
        # Likewise the samples: the default 4 a pixel at full size are 4 / scale^2 a pixel here,
        # so that an 8x8 block of this image averages as many camera samples as the 32x32
        # pixels of the full-size render it covers (a block error measured on fewer would be
        # the preview's noise, 4x the full-size render's per block at 4 samples a pixel).
        full_size = []
        if "--photon-scale" not in a.caustic_args and "--photons" not in a.caustic_args:
            a.caustic_args = (a.caustic_args + f" --photon-scale {1 / (a.scale * a.scale):g}").strip()
            full_size.append("photon counts")
        if "--spp" not in a.caustic_args:
            a.caustic_args = (a.caustic_args + f" --spp {round(4 / (a.scale * a.scale))}").strip()
            full_size.append("samples per image area")
        if full_size and a.label == "caustic defaults":
            a.label = "caustic defaults with the full-size render's " + " and ".join(full_size)
        a.out = a.out or os.path.join(PICS, "gltf.md")
    else:
        scenes = sorted(glob.glob(a.scenes or os.path.join(ROOT, "scenes", "validate", "*.lua")))
        a.scale = 1.0 if a.scale is None else a.scale
        a.out = a.out or os.path.join(ROOT, "docs", "validation.md")
    scale_args = [] if a.scale == 1.0 else ["--scale", repr(a.scale)]
    variant = choose_variant()
    os.makedirs(REFS, exist_ok=True)
    os.makedirs(PICS, exist_ok=True)
    tmp = tempfile.mkdtemp()
    rows, timing, times = [], [], []
    for scene in scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        xml = os.path.join(tmp, name + ".xml")
        subprocess.run([a.caustic, "export-mitsuba", scene, "-o", xml, "--spp", str(a.ref_spp)]
                       + scale_args, check=True, cwd=ROOT, stderr=subprocess.DEVNULL)
        ref = os.path.join(REFS, name + ".exr")
        side = os.path.join(REFS, name + ".json")
        second = os.path.join(REFS, name + ".second.exr")
        if a.render_refs or not os.path.exists(ref) or not os.path.exists(second):
            cpu, wall = render_mitsuba(xml, a.ref_spp, 1, ref)
            cpu2, wall2 = render_mitsuba(xml, a.ref_spp, 2, second)
            json.dump({"spp": a.ref_spp, "variant": variant, "cpu_s": cpu, "wall_s": wall,
                       "second_cpu_s": cpu2, "second_wall_s": wall2},
                      open(side, "w"), indent=1)
        info = json.load(open(side))
        r1, r2 = load(ref), load(second)
        own = sidecar_regions(a.regions, name) if a.regions else regions(scene)
        particle = None
        if any(reg.endswith("(ptracer)") for reg, _ in own):
            pt_xml = os.path.join(tmp, name + ".ptracer.xml")
            text = open(xml).read().replace('<integrator type="path">', '<integrator type="ptracer">')
            open(pt_xml, "w").write(text)
            pt1, pt2 = (os.path.join(REFS, name + s) for s in (".ptracer.exr", ".ptracer.second.exr"))
            if a.render_refs or not os.path.exists(pt1) or not os.path.exists(pt2):
                render_mitsuba(pt_xml, a.ref_spp, 1, pt1)
                render_mitsuba(pt_xml, a.ref_spp, 2, pt2)
            particle = (load(pt1), load(pt2))
        regs = [("image", (0, 0, 1, 1))] + own
        out = os.path.join(tmp, name + ".exr")
        args = a.caustic_args.split() + scale_args
        cpu, wall = caustic_render(a.render_with or a.caustic, scene, out, args)
        c = load(out)
        c2 = None
        if a.seeds > 1:
            out2 = os.path.join(tmp, name + ".seed.exr")
            caustic_render(a.render_with or a.caustic, scene, out2, args + ["--seed", "1"])
            c2 = load(out2)
        picture(c, 0.5 * (r1 + r2), os.path.join(PICS, name + ".png"))
        for reg, box in regs:
            q1, q2 = particle if reg.endswith("(ptracer)") else (r1, r2)
            rows.append((name, reg, metrics(c, q1, q2, box, c2), ref_noise(q1, q2, box)))
        if a.equal_time:
            spp = max(1, int(round(info["spp"] * cpu / max(info["cpu_s"], 1e-9))))
            eq = os.path.join(tmp, name + "_eq.exr")
            mcpu, _ = render_mitsuba(xml, spp, 7, eq)
            m = load(eq)
            for reg, box in regs:
                mc = metrics(c, r1, r2, box)["rel_rmse"]
                mm = metrics(m, r1, r2, box)["rel_rmse"]
                timing.append((name, reg, cpu, wall, spp, mcpu, mc, mm))
        times.append((name, info, cpu, wall))
        print(f"{name}: caustic {wall:.1f} s wall, {cpu:.1f} s CPU", file=sys.stderr)
    if a.gltf:
        write_gltf_md(a, variant, rows, times)
    else:
        write_md(a, variant, rows, timing)


def pic_link(a, name):
    """The picture's path relative to the Markdown file being written."""
    return os.path.relpath(os.path.join(PICS, name + ".png"), os.path.dirname(os.path.abspath(a.out)))


def table(rows):
    lines = [
        "| scene | region | mean ratio | RMSE | rel. RMSE | block error | bias | reference noise (rel. RMSE / block) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, reg, m, f in rows:
        fl = f"{f['rel_rmse']:.3f} / {f['block_bias']:.3f}"
        sb = f"{m['seed_bias']:.3f}" if "seed_bias" in m else "n/a"
        lines.append(f"| {name} | {reg} | {m['mean_ratio']:.4f} | {m['rmse']:.4f} | "
                     f"{m['rel_rmse']:.3f} | {m['block_bias']:.3f} | {sb} | {fl} |")
    return lines


def write_gltf_md(a, variant, rows, times):
    """The glTF section, to merge into docs/validation.md (whose metrics it shares)."""
    w, h = int(round(800 * a.scale)), int(round(600 * a.scale))
    regions_file = os.path.relpath(a.regions, ROOT)
    lines = [
        "## glTF scenes",
        "",
        "caustic's render of glTF files as whole scenes (`scenes/gltf/`, exported by Blender, see "
        "`tools/gltf_scenes/README.md`) against Mitsuba 3's path tracer "
        f"(`{variant}`) on the scene `caustic export-mitsuba SCENE.glb --scale {a.scale:g}` writes, "
        f"at {w}x{h} for the 4:3 cameras. Regenerate with:",
        "",
        "```sh",
        "tools/validate/.venv/bin/python tools/validate/run.py --gltf     # --render-refs to re-render the references",
        "```",
        "",
        f"Rendered: {a.label} (`caustic render SCENE.glb --scale {a.scale:g} {a.caustic_args}`). "
        f"Regions are in `{regions_file}`; the metrics are defined as for the `scenes/validate` table.",
        "",
    ] + table(rows) + [
        "",
        "Render times (Mitsuba: each reference; caustic: the seed-0 render):",
        "",
        "| scene | reference spp | reference 1 wall / CPU s | reference 2 wall / CPU s | caustic wall / CPU s |",
        "|---|---|---|---|---|",
    ]
    for name, info, cpu, wall in times:
        r2 = (f"{info['second_wall_s']:.1f} / {info['second_cpu_s']:.1f}"
              if "second_wall_s" in info else "n/a")
        lines.append(f"| {name} | {info['spp']} | {info['wall_s']:.1f} / {info['cpu_s']:.1f} | "
                     f"{r2} | {wall:.1f} / {cpu:.1f} |")
    lines += ["", "Pictures (reference | caustic | difference: red brighter, blue darker, 4x):", ""]
    for name in sorted({r[0] for r in rows}):
        lines.append(f"- `{name}`: ![{name}]({pic_link(a, name)})")
    open(a.out, "w").write("\n".join(lines) + "\n")
    print("\n".join(lines))


def write_md(a, variant, rows, timing):
    lines = [
        "# Validation against Mitsuba 3",
        "",
        "caustic's render of each scene in `scenes/validate/` against Mitsuba 3's path tracer "
        f"(`{variant}`) on the same scene, exported by `caustic export-mitsuba`. Regenerate with:",
        "",
        "```sh",
        "bash tools/validate/setup.sh && cargo build --release",
        "tools/validate/.venv/bin/python tools/validate/run.py            # --render-refs to re-render the references",
        "```",
        "",
        f"Rendered: {a.label} (`caustic render SCENE.lua {a.caustic_args}`). Metrics are over all three "
        "channels of each region (`-- region` comments in the scene), against the truth as "
        "estimated from two independent references r1 and r2: where a plain metric would square "
        "(c - r), these multiply (c - r1)(c - r2), whose expectation is the squared error against "
        "the truth, so the references' own noise drops out instead of adding to caustic's error. "
        "*Mean ratio* is caustic's mean over the references'; *RMSE* and *relative RMSE* (over the "
        "reference mean) are per pixel; *block error* is the same over the means of the 8x8-pixel "
        "blocks in the region, in which pixel noise averages out but the photon map's noise, "
        "correlated over a kernel's radius, partly survives; *bias* is the block error between "
        "two caustic renders of different seeds and the two references, from which caustic's own "
        "noise drops out as well: what more samples and photons at the same settings would not "
        "remove. *Reference noise* is one reference's own relative RMSE and block error (the two "
        "references' distance over sqrt 2). The bar (issue 13): mean within 2% and block error at "
        "most 3% in every region. The `image` row includes the visible light, whose edges one "
        "centre ray per pixel aliases (a box-filtered Mitsuba pixel averages them): it is "
        "reported, not part of the bar.",
        "",
    ] + table(rows)
    lines += ["", "Pictures (reference | caustic | difference: red brighter, blue darker, 4x):", ""]
    for name in sorted({r[0] for r in rows}):
        lines.append(f"- `{name}`: ![{name}](validation/{name}.png)")
    if timing:
        lines += ["", "## Equal time", "",
                  "Mitsuba's path tracer given caustic's CPU time (sample count scaled from the "
                  "reference's samples per CPU second); both relative RMSEs are against the truth "
                  "as estimated from the two references, as above:", "",
                  "| scene | region | caustic CPU s | Mitsuba spp | Mitsuba CPU s | caustic rel. RMSE | Mitsuba rel. RMSE | ratio |",
                  "|---|---|---|---|---|---|---|---|"]
        for name, reg, cpu, wall, spp, mcpu, mc, mm in timing:
            lines.append(f"| {name} | {reg} | {cpu:.1f} | {spp} | {mcpu:.1f} | {mc:.3f} | {mm:.3f} | {mc / mm:.2f} |")
    open(a.out, "w").write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
