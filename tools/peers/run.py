#!/usr/bin/env python3
"""caustic against its peers at equal CPU time: Mitsuba 3's references, LuxCore 2.11 (PATHCPU,
PATHCPU with the PhotonGI caustic cache, BIDIRCPU) and Blender Cycles 5.0 (path tracing, with
manifold next-event estimation, with path guiding), on the validation scenes with caustics.

    bash tools/peers/setup.sh && cargo build --release && python3 tools/peers/run.py

For each scene, caustic renders at its defaults (CPU seconds of the whole process by
/usr/bin/time); each peer then renders caustic's own Mitsuba export of the scene (read back by
tools/peers/scene.py: the same triangles, materials, light and camera for every peer) with a time
limit of caustic's CPU time over the 2 threads, and reports the CPU time its render took. Every
image is measured against the two Mitsuba references of tools/validate/refs with `caustic diff
--second` (the references' noise drops out) over the image below the ceiling light and each of
the scene's regions. The diffuse Cornell box, which has no caustic, is the light units' check:
every peer's mean over its image must be within 2% of the references' at a long time limit
(`--calibrate 20`: 20 s each). Writes its table into docs/peers.md (between the markers; a
run of a subset only prints it; `--report` writes both tables again from target/peers/*.json);
scratch images go to target/peers/.

Environment: LUX_PY and BPY_PY, the Pythons with pyluxcore and bpy (tools/peers/setup.sh makes
tools/peers/.venv-lux and .venv-bpy); PEERS=lux_path,... to run a subset; SCENES=a,b likewise.
"""

import argparse
import json
import os
import re
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BIN = os.path.join(ROOT, "target", "release", "caustic")
REFS = os.path.join(ROOT, "tools", "validate", "refs")
OUT = os.path.join(ROOT, "target", "peers")
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "validate"))
from regions import pixels, regions  # noqa: E402

SCENES = ["cornell_diffuse", "cornell_glass", "cornell_mirror", "glass_in_water"]
PEERS = {
    "lux_path": ("LuxCore PATHCPU", "lux", ["--engine", "path"]),
    "lux_photongi": ("LuxCore PATHCPU + PhotonGI caustics", "lux", ["--engine", "path_photongi"]),
    "lux_bidir": ("LuxCore BIDIRCPU", "lux", ["--engine", "bidir"]),
    "cycles_path": ("Cycles path", "bpy", ["--mode", "path"]),
    "cycles_mnee": ("Cycles path + MNEE", "bpy", ["--mode", "mnee"]),
    "cycles_guiding": ("Cycles path + guiding", "bpy", ["--mode", "guiding"]),
}


def python_for(kind):
    if kind == "lux":
        return os.environ.get("LUX_PY", os.path.join(HERE, ".venv-lux", "bin", "python"))
    default = os.path.join(HERE, ".venv-bpy", "bin", "python")
    return os.environ.get("BPY_PY", default)


def diff(image, name, box):
    out = subprocess.run(
        [BIN, "diff", image, os.path.join(REFS, name + ".exr"), "--second",
         os.path.join(REFS, name + ".second.exr"), "--region", ",".join(map(str, box))],
        check=True, capture_output=True, text=True).stdout
    get = lambda k: float(re.search(k + r"\s+([-+0-9.eE]+)", out).group(1))  # noqa: E731
    return {"rel": get("relative RMSE"), "ratio": get("mean ratio")}


def caustic(name, lua, seed, tag="caustic", args=()):
    img = os.path.join(OUT, name, f"{tag}.{seed}.exr")
    tfile = os.path.join(OUT, name, f"{tag}.time")
    subprocess.run(["/usr/bin/time", "-f", "%e %U %S", "-o", tfile, BIN, "render", lua, "-q",
                    "--seed", str(seed), "-o", img, *args], check=True, capture_output=True)
    e, u, s = open(tfile).read().split()[-3:]
    return img, float(u) + float(s), float(e)


def peer(key, name, xml, seconds, seed):
    _, kind, args = PEERS[key]
    img = os.path.join(OUT, name, f"{key}.{seed}.exr")
    script = os.path.join(HERE, "luxcore_render.py" if kind == "lux" else "cycles_render.py")
    cmd = [python_for(kind), script, xml, img, "--seconds", f"{seconds:.3f}", "--seed",
           str(seed)] + args
    if kind == "bpy":
        cmd = [python_for(kind), script, "--", xml, img, "--seconds", f"{seconds:.3f}",
               "--seed", str(seed)] + args
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"peers: {key} on {name} failed:\n{p.stderr[-3000:]}")
    line = [ln for ln in p.stdout.splitlines() if ln.startswith("{")][-1]
    return img, json.loads(line)["cpu"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--calibrate", type=float, default=0.0,
                    help="only the light units' check: each peer on the diffuse box for this many seconds")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--report", action="store_true",
                    help="only write docs/peers.md's tables again from target/peers/*.json")
    a = ap.parse_args()
    if a.report:
        for name, cal in (("peers.json", False), ("calibration.json", True)):
            path = os.path.join(OUT, name)
            if os.path.exists(path):
                write_doc(report(json.load(open(path)), cal), cal)
        return
    peers = os.environ.get("PEERS", ",".join(PEERS)).split(",")
    scenes = os.environ.get("SCENES", ",".join(SCENES)).split(",")
    if a.calibrate:
        scenes = ["cornell_diffuse"]
    rows = []
    for name in scenes:
        lua = os.path.join(ROOT, "scenes", "validate", name + ".lua")
        os.makedirs(os.path.join(OUT, name), exist_ok=True)
        xml = os.path.join(OUT, name, name + ".xml")
        subprocess.run([BIN, "export-mitsuba", lua, "-o", xml], check=True, capture_output=True)
        w = h = 96
        boxes = [("image", (0, 8, w, h))] + [(n, pixels(b, w, h)) for n, b in regions(lua)]
        if a.calibrate:
            entries = []
            seconds = a.calibrate
        else:
            img, cpu, wall = caustic(name, lua, a.seed)
            entries = [("caustic", "caustic (defaults)", img, cpu)]
            seconds = cpu / 2
            # The time planner given the defaults' wall time less the scene's reading and
            # build (0.2 s here), which a budget does not count (as
            # tools/accuracy/final_budget.sh).
            budget = max(0.1, wall - 0.2)
            img, bcpu, _ = caustic(name, lua, a.seed, "caustic_budget",
                                   ("--time-budget", f"{budget:.2f}"))
            entries.append(("caustic_budget", "caustic --time-budget", img, bcpu))
        for key in peers:
            img, cpu = peer(key, name, xml, seconds, a.seed)
            entries.append((key, PEERS[key][0], img, cpu))
            print(f"{name}: {key} {cpu:.1f} s CPU", file=sys.stderr)
        for region, box in boxes:
            for key, label, img, cpu in entries:
                m = diff(img, name, box)
                rows.append({"scene": name, "region": region, "who": key, "label": label,
                             "cpu": cpu, **m})
    os.makedirs(OUT, exist_ok=True)
    path = os.path.join(OUT, "calibration.json" if a.calibrate else "peers.json")
    json.dump(rows, open(path, "w"), indent=1)
    table = report(rows, a.calibrate)
    print(table)
    if not os.environ.get("PEERS") and not os.environ.get("SCENES"):
        write_doc(table, bool(a.calibrate))


def write_doc(table, calibration):
    """Puts `table` between docs/peers.md's markers for it."""
    doc = os.path.join(ROOT, "docs", "peers.md")
    mark = "calibration" if calibration else "table"
    text = open(doc).read()
    start, end = f"<!-- {mark} -->", f"<!-- /{mark} -->"
    if start not in text or end not in text:
        raise SystemExit(f"peers: docs/peers.md has no {start} ... {end}")
    head, rest = text.split(start, 1)
    _, tail = rest.split(end, 1)
    open(doc, "w").write(f"{head}{start}\n{table}\n{end}{tail}")


def report(rows, calibrate):
    out = []
    if calibrate:
        out.append("| peer | CPU s | mean ratio to Mitsuba (image) |")
        out.append("|---|---|---|")
        for r in rows:
            if r["region"] == "image":
                out.append(f"| {r['label']} | {r['cpu']:.1f} | {r['ratio']:.4f} |")
        return "\n".join(out)
    keys = []
    for r in rows:
        if r["who"] not in keys:
            keys.append(r["who"])
    labels = {r["who"]: r["label"] for r in rows}
    out.append("| scene | region | " + " | ".join(labels[k] for k in keys)
               + " | caustic / best peer | budget / best peer |")
    out.append("|---|---|" + "---|" * (len(keys) + 2))
    cells = {}
    for r in rows:
        cells[(r["scene"], r["region"], r["who"])] = r
    seen = []
    for r in rows:
        if (r["scene"], r["region"]) in seen:
            continue
        seen.append((r["scene"], r["region"]))
        line = f"| {r['scene']} | {r['region']} |"
        ours = ("caustic", "caustic_budget")
        best = min((cells[(r['scene'], r['region'], k)]["rel"] for k in keys if k not in ours
                    and (r['scene'], r['region'], k) in cells), default=float("nan"))
        for k in keys:
            c = cells.get((r["scene"], r["region"], k))
            line += f" {c['rel']:.4f} ({c['cpu']:.1f} s, mean x{c['ratio']:.3f}) |" if c else " |"
        for k in ours:
            mine = cells.get((r["scene"], r["region"], k))
            line += f" {mine['rel'] / best:.2f} |" if mine and best == best else " |"
        out.append(line)
    return "\n".join(out)


if __name__ == "__main__":
    main()
