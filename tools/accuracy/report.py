#!/usr/bin/env python3
"""Writes docs/accuracy.md (to stdout) from the studies tools/accuracy/run.sh left in DOCS:
per scene the photon mapper's and the progressive integrator's tables and plots (caustic
study's Markdown), Mitsuba 3's curve, fitted slopes, and advice computed from them."""

import csv
import math
import os
import sys

SCENES = [
    ("cornell_diffuse", "A diffuse Cornell box (`scenes/validate/cornell_diffuse.lua`, 96 x 96, area light)"),
    ("glass_in_water", "A glass ball casting a caustic through water (`scenes/validate/glass_in_water.lua`, 96 x 96)"),
    ("showcase", "The showcase scene (`scenes/cornell_glass.lua` at `--scale 0.25`, 100 x 100)"),
]


def summaries(path):
    """(setting, mean CPU s, RMS relative RMSE) per point, in file order."""
    groups = {}
    for row in csv.DictReader(open(path)):
        g = groups.setdefault(row["point"], [row.get("setting", row["point"]), [], []])
        g[1].append(float(row["cpu_s"]))
        g[2].append(float(row["rel_rmse"]))
    return [(s, sum(t) / len(t), math.sqrt(sum(e * e for e in es) / len(es)))
            for s, t, es in groups.values()]


def fit(points):
    """Least-squares (slope, intercept) of ln error against ln time."""
    xs = [math.log(t) for _, t, e in points if t > 0 and e > 0]
    ys = [math.log(e) for _, t, e in points if t > 0 and e > 0]
    n = len(xs)
    if n < 2:
        return None
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx
    return b, my - b * mx


def pareto(points):
    return [p for p in points
            if not any((o[1] <= p[1] and o[2] < p[2]) or (o[1] < p[1] and o[2] <= p[2]) for o in points)]


def time_for(error, line):
    b, a = line
    return math.exp((math.log(error) - a) / b)


def first_key(setting):
    return setting.split()[0].split("=")[0]


def rate(slope, what):
    """A sentence on what halving the error costs at this slope."""
    if slope > -0.1:
        return (f"error ∝ time^{slope:.2f}: more {what} barely lowers the error; it is at the "
                f"setting's bias (the seed-pair column)")
    if slope < -0.6:
        return (f"error ∝ time^{slope:.2f} over the range studied, faster than Monte Carlo's "
                f"-1/2 because the photon passes' fixed cost is spread over more {what}; beyond "
                f"it, expect -1/2 (halving the error takes 4x the time)")
    return f"error ∝ time^{slope:.2f}: halving the error takes {2 ** (-1 / slope):.0f}x the time"


def advice(name, pm, prog, mi):
    out = []
    series = {}
    key0 = first_key(pm[0][0])
    for s, t, e in pm:
        key = " ".join(kv for kv in s.split() if not kv.startswith(key0 + "="))
        series.setdefault(key, []).append((s, t, e))
    for key, pts in series.items():
        line = fit(pts)
        if line:
            out.append(f"- Photon mapping at {key}, more {key0}: {rate(line[0], key0)}.")
    keys = list(series)
    if len(keys) == 2:
        a, b = series[keys[0]], series[keys[1]]
        ratios = [(pb[2] / pa[2], pb[1] / pa[1]) for pa, pb in zip(a, b)]
        er = sum(r[0] for r in ratios) / len(ratios)
        tr = sum(r[1] for r in ratios) / len(ratios)
        verdict = "pays off" if er < tr ** -0.5 else "does not pay off"
        out.append(f"- {keys[1]} instead of {keys[0]} (at each {key0}): {tr:.1f}x the time for "
                   f"{er:.2f}x the error; against spending that time on more {key0} "
                   f"(error ∝ time^-1/2 at best), it {verdict}.")
    pl = fit(prog)
    if pl:
        out.append(f"- Progressive photon mapping, more passes: {rate(pl[0], 'passes')} "
                   f"(-1/3 is the kernel's rate; -1/2 means the Monte Carlo terms, camera samples, "
                   f"shadow and gather rays, still dominate).")
    ml = fit(mi)
    if ml:
        e60 = math.exp(ml[1] + ml[0] * math.log(60))
        best = sorted(pareto(pm + prog), key=lambda p: p[1])
        reach = [p for p in best if p[2] <= e60]
        out.append(f"- Mitsuba 3's path tracer: error ∝ time^{ml[0]:.2f}; its fitted error at 60 s "
                   f"CPU is {e60:.4f}.")
        if reach:
            s, t, e = reach[0]
            out.append(f"  caustic reaches that error in {t:.1f} s CPU ({s}, {e:.4f}), "
                       f"{60 / t:.1f}x sooner.")
        else:
            s, t, e = best[-1]
            out.append(f"  caustic's most accurate setting studied ({s}) has error {e:.4f} in "
                       f"{t:.1f} s, where Mitsuba's fit gives "
                       f"{math.exp(ml[1] + ml[0] * math.log(t)):.4f} at the same time.")
        for s, t, e in best[:1]:
            m = math.exp(ml[1] + ml[0] * math.log(t))
            out.append(f"  At caustic's fastest Pareto setting ({s}: {t:.1f} s, {e:.4f}) "
                       f"Mitsuba's fit gives {m:.4f}; to match {e:.4f} it needs "
                       f"{time_for(e, ml):.1f} s.")
    return out


def section(docs, name, title):
    d = os.path.join(docs, name)
    pm = summaries(os.path.join(d, "photon_map.csv"))
    prog = summaries(os.path.join(d, "progressive.csv"))
    mi = summaries(os.path.join(d, "mitsuba.csv"))
    lines = [f"## {title}", ""]
    for kind in ("photon_map", "progressive"):
        md = open(os.path.join(d, kind + ".md")).read()
        md = md.replace("](study.png)", f"](accuracy/{name}/{kind}.png)")
        md = md.replace("## ", "### ", 1)
        lines += [md, ""]
    lines += ["### Mitsuba 3's path tracer", "", "| spp | CPU s | rel. RMSE |", "|---|---|---|"]
    lines += [f"| {s.split('=')[1]} | {t:.2f} | {e:.4f} |" for s, t, e in mi]
    target = os.path.join(d, "target.csv")
    if os.path.exists(target):
        lines += ["", "### `--target-error`", "",
                  "| target | passes | seconds (wall) | estimated | actual (vs Mitsuba) | actual / target |",
                  "|---|---|---|---|---|---|"]
        for row in csv.DictReader(open(target)):
            ratio = float(row["actual"]) / float(row["target"])
            lines.append(f"| {row['target']} | {row['passes']} | {row['seconds']} | {row['estimated']} "
                         f"| {float(row['actual']):.4f} | {ratio:.2f} |")
    lines += ["", "### What it means", ""] + advice(name, pm, prog, mi) + [""]
    best = sorted(pareto(pm + prog), key=lambda p: p[1])
    lines += ["Pareto settings (photon mapper and progressive together): "
              + "; ".join(f"{s} ({t:.1f} s, {e:.4f})" for s, t, e in best), ""]
    return lines


def main():
    docs = sys.argv[1]
    head = [
        "# What accuracy costs: error against time",
        "",
        "Regenerate (on an idle machine; about 15 minutes on 2 cores):",
        "",
        "```sh",
        "bash tools/validate/setup.sh && cargo build --release && bash tools/accuracy/run.sh",
        "```",
        "",
        "Each scene is rendered by the photon mapper over a grid of settings, by the progressive "
        "integrator (`--integrator progressive`) over passes, and by Mitsuba 3's path tracer over "
        "samples per pixel, all measured against two independent 4096-spp (the showcase: 2048-spp) Mitsuba "
        "references with `caustic study` (`(c - r1)(c - r2)` products, so the references' noise "
        "drops out; see `docs/validation.md`). Errors are relative RMSE over the image below the "
        "ceiling light (whose edges alias at a few camera samples per pixel, which a 1024-spp path "
        "tracer averages away: in the whole image that one row of pixels would drown the rest), "
        "averaged over two seeds; times are CPU "
        "seconds of the whole process (scene build, photon passes, camera pass; for Mitsuba the "
        "render after a warm-up that compiles its kernels), on the project's 2-core VM. "
        "*Block error* is the same over 8x8-block means, *seed-pair bias* the block error between "
        "two seeds' images and the two references, from which noise drops out: a setting's "
        "bias, which its own noise hides in a single render. Bold rows are on the Pareto front "
        "(nothing else is both faster and more accurate). Slopes are fitted to log error "
        "against log time: pure Monte Carlo converges at -1/2, progressive photon mapping at "
        "-1/3 asymptotically.",
        "",
        "How to read it. A photon-mapped pixel's error has three parts: the camera's, shadow rays' "
        "and final-gather rays' Monte Carlo noise (falls as time^-1/2 with `--spp`), the photon "
        "maps' noise and blur (fall with `--photons`/`--caustic-photons`, slowly) and their bias "
        "(the seed-pair column: what no number of camera samples removes). Where more `--spp` "
        "stops paying, the maps are the limit, and the progressive integrator, whose bias falls with "
        "passes, is the way further. Its own slope here is near -1/2 because at these pass counts "
        "the Monte Carlo terms still dominate; on a scene with no Monte Carlo term (the closed-form "
        "mirror caustic of `tests/light_transport/progressive.rs`) it falls at -0.31 against "
        "passes, the -1/3 progressive photon mapping predicts.",
        "",
    ]
    body = []
    for name, title in SCENES:
        if os.path.exists(os.path.join(docs, name, "photon_map.csv")):
            body += section(docs, name, title)
    # Studies of their own, each linked under its heading when its page is there.
    for page, title, text in [
        ("adaptive.md", "Adaptive pixels",
         "`--noise-target` against uniform `--spp` at equal CPU time on these three scenes "
         "(`tools/accuracy/adaptive.sh`)"),
        ("budget.md", "A time budget or a target error",
         "`--time-budget` against the defaults with more samples and against a grid of "
         "`--spp` and `--photon-scale`, at equal CPU time, on these three scenes and the final "
         "scene at a quarter of its size (`tools/accuracy/budget.sh`)"),
    ]:
        if os.path.exists(os.path.join(docs, page)):
            body += ["", f"## {title}", "", f"{text}: [accuracy/{page}](accuracy/{page})."]
    print("\n".join(head + body))


if __name__ == "__main__":
    main()
