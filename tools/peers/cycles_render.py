#!/usr/bin/env python3
"""Renders caustic's Mitsuba export of a scene with Blender Cycles (`bpy` 5.0.1 from PyPI).

    cycles_render.py SCENE.xml OUT.exr --mode path|mnee|guiding --seconds S [--seed N]

Modes: path tracing; path tracing with manifold next-event estimation (Cycles' "shadow
caustics": the light is an area light object, the dielectrics cast and the diffuse surfaces
receive); path tracing with path guiding (surface guiding, CPU). All set up to converge to the
same image as Mitsuba: no clamping, no glossy filter, caustics on, 64 bounces of every kind, no
denoiser, a box pixel filter one pixel wide, the Raw view (linear EXR), two threads, the render
stopped by Cycles' own time limit (adaptive sampling on, its threshold low enough that the
limit, not the threshold, ends it). Prints one JSON line: the render's CPU seconds (this
process's user + system time across `render()`; loading bpy and building the scene excluded)
and its samples.

Light units: a mesh light is an Emission shader of strength 1 whose colour is the radiance (on
the front side only: the back is black, as Mitsuba's one-sided area emitter); the area light
object of the MNEE mode has power `L·π·A` (Cycles' area light radiance is `P/(π·A)`). Both are
checked on the diffuse Cornell box against Mitsuba's references (run.sh's calibration rows:
mean ratio within 2%).
"""

import json
import math
import os
import sys

import bpy
import numpy as np
from mathutils import Matrix

sys.path.insert(0, os.path.dirname(__file__))
import scene as sc  # noqa: E402


def set_flag(owner, names, value):
    """Sets the first of `names` that `owner` (or its `cycles` settings) has."""
    for target in (owner, getattr(owner, "cycles", None)):
        for n in names:
            if target is not None and hasattr(target, n):
                setattr(target, n, value)
                return True
    return False


def material(name, m, radiance):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    if m["type"] == "diffuse":
        b = nt.nodes.new("ShaderNodeBsdfDiffuse")
        b.inputs["Color"].default_value = (*m["reflectance"], 1)
        b.inputs["Roughness"].default_value = 0.0
    elif m["type"] == "dielectric":
        b = nt.nodes.new("ShaderNodeBsdfGlass")
        b.inputs["Color"].default_value = (1, 1, 1, 1)
        b.inputs["Roughness"].default_value = 0.0
        b.inputs["IOR"].default_value = m["int_ior"] / m["ext_ior"]
    elif m["type"] == "mirror":
        b = nt.nodes.new("ShaderNodeBsdfGlossy")
        b.inputs["Color"].default_value = (*m["reflectance"], 1)
        b.inputs["Roughness"].default_value = 0.0
    shader = b.outputs[0]
    if radiance is not None:
        e = nt.nodes.new("ShaderNodeEmission")
        e.inputs["Color"].default_value = (*radiance, 1)
        e.inputs["Strength"].default_value = 1.0
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(e.outputs[0], add.inputs[0])
        nt.links.new(shader, add.inputs[1])
        geo = nt.nodes.new("ShaderNodeNewGeometry")
        mix = nt.nodes.new("ShaderNodeMixShader")
        nt.links.new(geo.outputs["Backfacing"], mix.inputs["Fac"])
        nt.links.new(add.outputs[0], mix.inputs[1])
        nt.links.new(shader, mix.inputs[2])
        shader = mix.outputs[0]
    nt.links.new(shader, out.inputs["Surface"])
    return mat


def area_light(shape, radiance):
    """An area light object on the emitting rectangle (two triangles of `shape`), facing where
    the rectangle's normal faces, of the power that gives radiance `radiance`."""
    v = shape["vertices"]
    centre = v.mean(axis=0)
    ex, ey = v[1] - v[0], v[3] - v[0]
    sx, sy = np.linalg.norm(ex), np.linalg.norm(ey)
    n = np.cross(ex, ey)
    n /= np.linalg.norm(n)
    x, y, z = ex / sx, -ey / sy, -n  # the light shines along its local -Z, i.e. along n
    data = bpy.data.lights.new("area", "AREA")
    data.shape = "RECTANGLE"
    data.size, data.size_y = float(sx), float(sy)
    peak = max(radiance)
    data.color = tuple(c / peak for c in radiance)
    data.energy = float(peak * math.pi * sx * sy)
    set_flag(data, ("is_caustics_light",), True)
    obj = bpy.data.objects.new("area", data)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, y, z, centre
    obj.matrix_world = Matrix([list(r) for r in m])  # rows
    bpy.context.scene.collection.objects.link(obj)


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    a = sc.arguments("--mode", ("path", "mnee", "guiding"), argv)
    s = sc.read(a.xml)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    for i, shape in enumerate(s["shapes"]):
        if a.mode == "mnee" and shape["radiance"] is not None:
            area_light(shape, shape["radiance"])
            continue
        mesh = bpy.data.meshes.new(f"m{i}")
        mesh.from_pydata([tuple(p) for p in shape["vertices"]], [],
                         [tuple(int(t) for t in f) for f in shape["faces"]])
        mesh.update()
        if shape["normals"] is not None:
            mesh.shade_smooth()
        mesh.materials.append(material(f"mat{i}", shape["material"], shape["radiance"]))
        obj = bpy.data.objects.new(f"o{i}", mesh)
        scene.collection.objects.link(obj)
        if a.mode == "mnee":
            kind = shape["material"]["type"]
            set_flag(obj, ("is_caustics_caster",), kind in ("dielectric", "mirror"))
            set_flag(obj, ("is_caustics_receiver",), kind == "diffuse")
    cam = s["camera"]
    cdata = bpy.data.cameras.new("cam")
    # The vertical field of view through the lens on a 24 mm tall sensor fitted vertically.
    cdata.sensor_fit = "VERTICAL"
    cdata.sensor_height = 24.0
    cdata.lens = 12.0 / math.tan(math.radians(cam["fov_y"]) / 2)
    cdata.clip_start, cdata.clip_end = 1e-3, 1e4
    cobj = bpy.data.objects.new("cam", cdata)
    o, t, up = (np.array(cam[k], float) for k in ("origin", "target", "up"))
    fwd = (t - o) / np.linalg.norm(t - o)
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    true_up = np.cross(right, fwd)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = right, true_up, -fwd, o
    cobj.matrix_world = Matrix([list(r) for r in m])  # rows
    scene.collection.objects.link(cobj)
    scene.camera = cobj
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world

    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = cam["width"], cam["height"], 100
    r.threads_mode, r.threads = "FIXED", 2
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    r.filepath = os.path.abspath(a.out)
    scene.view_settings.view_transform = "Raw"
    c = scene.cycles
    c.device = "CPU"
    c.samples = 1 << 24
    c.time_limit = a.seconds
    c.use_adaptive_sampling = True
    c.adaptive_threshold = 0.0001
    c.use_denoising = False
    c.seed = a.seed
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = c.caustics_refractive = True
    for k in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
              "transparent_max_bounces", "volume_bounces"):
        setattr(c, k, 64)
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    if a.mode == "guiding":
        c.use_guiding = True
        c.use_surface_guiding = True
        c.use_volume_guiding = False
    c0 = sc.cpu()
    bpy.ops.render.render(write_still=True)
    c1 = sc.cpu()
    print(json.dumps({"cpu": c1 - c0}))


if __name__ == "__main__":
    main()
