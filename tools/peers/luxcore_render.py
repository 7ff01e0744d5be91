#!/usr/bin/env python3
"""Renders caustic's Mitsuba export of a scene with LuxCore 2.11 (`pyluxcore` from PyPI).

    luxcore_render.py SCENE.xml OUT.exr --engine path|path_photongi|bidir --seconds S [--seed N]

Engines: PATHCPU (Sobol sampler), PATHCPU with the PhotonGI caustic cache (LuxCore's own answer
to caustics a path tracer finds too rarely), BIDIRCPU (random sampler). Two threads, a box
pixel filter half a pixel wide (Mitsuba's box), no clamping, unbounded depth as far as LuxCore
allows (its path depth cap set to 64 bounces, with Russian roulette). Prints one JSON line: the
render's CPU seconds (this process's user + system time across the render, scene parsing
excluded as for Mitsuba's warm-up) and its samples per pixel.

Light units: an emitting triangle's `emission` is its radiance (`emission.gain` 1, power and
efficiency 0 so that LuxCore does not normalise it), checked on the diffuse Cornell box against
Mitsuba's references (run.sh's calibration row: mean ratio within 2%).
"""

import json
import os
import struct
import sys
import tempfile
import time

import pyluxcore

sys.path.insert(0, os.path.dirname(__file__))
import scene as sc  # noqa: E402


def write_ply(path, v, f, n):
    with open(path, "wb") as out:
        head = ["ply", "format binary_little_endian 1.0", f"element vertex {len(v)}",
                "property float x", "property float y", "property float z"]
        if n is not None:
            head += ["property float nx", "property float ny", "property float nz"]
        head += [f"element face {len(f)}", "property list uchar int vertex_indices",
                 "end_header"]
        out.write(("\n".join(head) + "\n").encode())
        for i in range(len(v)):
            row = list(v[i]) + (list(n[i]) if n is not None else [])
            out.write(struct.pack(f"<{len(row)}f", *row))
        for tri in f:
            out.write(struct.pack("<Biii", 3, *(int(t) for t in tri)))


def main():
    a = sc.arguments("--engine", ("path", "path_photongi", "bidir"))
    s = sc.read(a.xml)
    pyluxcore.Init(lambda msg: None)
    tmp = tempfile.mkdtemp(prefix="caustic_lux_")
    lines = []
    cam = s["camera"]
    fmt = lambda v: " ".join(f"{x:.9g}" for x in v)  # noqa: E731
    lines += [
        'scene.camera.type = "perspective"',
        f"scene.camera.lookat.orig = {fmt(cam['origin'])}",
        f"scene.camera.lookat.target = {fmt(cam['target'])}",
        f"scene.camera.up = {fmt(cam['up'])}",
        f"scene.camera.fieldofview = {cam['fov_y']}",
    ]
    for i, shape in enumerate(s["shapes"]):
        ply = os.path.join(tmp, f"s{i}.ply")
        write_ply(ply, shape["vertices"], shape["faces"], shape["normals"])
        m = shape["material"]
        name = f"m{i}"
        if m["type"] == "diffuse":
            lines += [f'scene.materials.{name}.type = "matte"',
                      f"scene.materials.{name}.kd = {fmt(m['reflectance'])}"]
        elif m["type"] == "dielectric":
            lines += [f'scene.materials.{name}.type = "glass"',
                      f"scene.materials.{name}.kr = 1 1 1",
                      f"scene.materials.{name}.kt = 1 1 1",
                      f"scene.materials.{name}.interiorior = {m['int_ior']}",
                      f"scene.materials.{name}.exteriorior = {m['ext_ior']}"]
        elif m["type"] == "mirror":
            lines += [f'scene.materials.{name}.type = "mirror"',
                      f"scene.materials.{name}.kr = {fmt(m['reflectance'])}"]
        if shape["radiance"] is not None:
            lines += [f"scene.materials.{name}.emission = {fmt(shape['radiance'])}",
                      f"scene.materials.{name}.emission.gain = 1 1 1",
                      f"scene.materials.{name}.emission.power = 0",
                      f"scene.materials.{name}.emission.efficency = 0",
                      f"scene.materials.{name}.emission.normalizebycolor = 0"]
        lines += [f'scene.shapes.s{i}.type = "mesh"', f'scene.shapes.s{i}.ply = "{ply}"',
                  f'scene.objects.o{i}.shape = "s{i}"', f'scene.objects.o{i}.material = "{name}"']
    scene_props = pyluxcore.Properties()
    scene_props.SetFromString("\n".join(lines))
    scene = pyluxcore.Scene()
    scene.Parse(scene_props)
    engine = {"path": "PATHCPU", "path_photongi": "PATHCPU", "bidir": "BIDIRCPU"}[a.engine]
    sampler = "RANDOM" if a.engine == "bidir" else "SOBOL"
    cfg = [
        f'renderengine.type = "{engine}"',
        f'sampler.type = "{sampler}"',
        f"renderengine.seed = {a.seed}",
        "native.threads.count = 2",
        f"film.width = {cam['width']}",
        f"film.height = {cam['height']}",
        'film.filter.type = "BOX"',
        "film.filter.width = 0.5",
        'film.outputs.0.type = "RGB"',
        f'film.outputs.0.filename = "{os.path.abspath(a.out)}"',
        "path.pathdepth.total = 64",
        "path.pathdepth.diffuse = 64",
        "path.pathdepth.glossy = 64",
        "path.pathdepth.specular = 64",
        "path.clamping.variance.maxvalue = 0",
        "path.forceblackbackground.enable = 1",
        "light.maxdepth = 64",
        "path.maxdepth = 64",
        f"batch.halttime = {a.seconds}",
    ]
    if a.engine == "path_photongi":
        # LuxCore's defaults trace up to 20M photons before the first pass (minutes here,
        # beyond any budget of this table) and look caustics up within 0.15 scene units (a
        # fourteenth of the box). A user would set the photons to the time given and the radius
        # to the scene: 100k photons a second of budget, a radius of 1% of the box, shrinking
        # as the cache is rebuilt every 8 passes (LuxCore's progressive update).
        photons = max(100_000, int(100_000 * a.seconds))
        cfg += ["path.photongi.caustic.enabled = 1", "path.photongi.indirect.enabled = 0",
                f"path.photongi.photon.maxcount = {photons}",
                f"path.photongi.caustic.maxsize = {photons}",
                "path.photongi.caustic.lookup.radius = 0.02",
                "path.photongi.caustic.updatespp = 8"]
    cfg_props = pyluxcore.Properties()
    cfg_props.SetFromString("\n".join(cfg))
    config = pyluxcore.RenderConfig(cfg_props, scene)
    session = pyluxcore.RenderSession(config)
    c0, w0 = sc.cpu(), time.time()
    session.Start()
    while not session.HasDone():
        time.sleep(0.05)
        session.UpdateStats()
    session.Stop()
    c1, w1 = sc.cpu(), time.time()
    stats = session.GetStats()
    spp = stats.Get("stats.renderengine.pass").GetFloat() if stats.IsDefined(
        "stats.renderengine.pass") else float("nan")
    session.GetFilm().SaveOutputs()
    print(json.dumps({"cpu": c1 - c0, "wall": w1 - w0, "spp": spp}), flush=True)
    # pyluxcore 2.11 crashes in its teardown at the interpreter's exit (a segmentation fault
    # after everything is written): leave without it.
    sys.stderr.flush()
    os._exit(0)


if __name__ == "__main__":
    main()
