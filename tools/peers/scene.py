"""The scene a peer renders: caustic's Mitsuba export (`caustic export-mitsuba`) read back into
triangles, materials and a camera that LuxCore and Cycles are both given the same way.

Only the subset the accuracy scenes use is read; anything else stops the tool with the element
at fault (never a silent approximation, as the exporter itself does):
- shapes: `cube` (Mitsuba's [-1, 1]^3 under `to_world`), `rectangle` ([-1, 1]^2 at z = 0, facing
  +z), `sphere` (centre and radius: tessellated finely, with exact radial vertex normals so that
  shading is smooth; the same mesh for every peer) and `obj` meshes;
- BSDFs: `diffuse` (inside `twosided`), `dielectric` (`int_ior`, `ext_ior`), `conductor`
  (`specular_reflectance`, a perfect mirror);
- emitters: `area` of constant `radiance`, one-sided (the side the shape's normal faces);
- the sensor: `perspective`, `fov` along y, `lookat`, the film's width and height.
"""

import argparse
import math
import os
import resource
import xml.etree.ElementTree as ET

import numpy as np

# The sphere's tessellation: rings x segments quads. At 256 x 512 a ball of radius 0.3 deviates
# from the true sphere by at most r(1 - cos(pi/512)) = 6e-6, far below a pixel's footprint.
SPHERE_RINGS = 256
SPHERE_SEGMENTS = 512


class SceneError(Exception):
    pass


def _floats(text):
    return [float(v) for v in text.replace(",", " ").split()]


def _rgb(el, name, default=None):
    for c in el:
        if c.get("name") == name and c.tag in ("rgb", "spectrum"):
            v = _floats(c.get("value"))
            return v * 3 if len(v) == 1 else v
        if c.get("name") == name and c.tag == "float":
            return [float(c.get("value"))] * 3
    if default is None:
        raise SceneError(f"<{el.tag} type={el.get('type')!r}> has no {name!r}")
    return default


def _float(el, name, default=None):
    for c in el:
        if c.get("name") == name and c.tag == "float":
            return float(c.get("value"))
    if default is None:
        raise SceneError(f"<{el.tag} type={el.get('type')!r}> has no float {name!r}")
    return default


def _to_world(shape):
    t = shape.find("transform")
    if t is None:
        return np.eye(4)
    m = t.find("matrix")
    if m is None or len(t) != 1:
        raise SceneError(f"shape {shape.get('type')}: only a <matrix> to_world is read")
    return np.array(_floats(m.get("value"))).reshape(4, 4)


def _transform(m, v, n=None):
    v = v @ m[:3, :3].T + m[:3, 3]
    if n is not None:
        n = n @ np.linalg.inv(m[:3, :3])
        n /= np.linalg.norm(n, axis=1, keepdims=True)
    return v, n


def _cube():
    v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    # Each face as two triangles wound so that the normal points outwards.
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    f = []
    for a, b, c, d in quads:
        f += [(a, b, c), (a, c, d)]
    return v, np.array(f), None


def _rectangle():
    v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    return v, np.array([(0, 1, 2), (0, 2, 3)]), None


def _sphere(centre, radius):
    rows = []
    for i in range(SPHERE_RINGS + 1):
        theta = math.pi * i / SPHERE_RINGS
        for j in range(SPHERE_SEGMENTS):
            phi = 2 * math.pi * j / SPHERE_SEGMENTS
            rows.append((math.sin(theta) * math.cos(phi), math.cos(theta),
                         math.sin(theta) * math.sin(phi)))
    n = np.array(rows)
    f = []
    s = SPHERE_SEGMENTS
    for i in range(SPHERE_RINGS):
        for j in range(s):
            a, b = i * s + j, i * s + (j + 1) % s
            c, d = a + s, b + s
            if i > 0:
                f.append((a, b, c))
            if i < SPHERE_RINGS - 1:
                f.append((b, d, c))
    f = np.array(f)
    # Outward winding: flip the triangles whose geometric normal points inwards.
    v = n * radius + np.asarray(centre)
    g = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    inward = np.einsum("ij,ij->i", g, n[f[:, 0]]) < 0
    f[inward] = f[inward][:, ::-1]
    return v, f, n


def _obj(path):
    v, n, f = [], [], []
    for line in open(path):
        p = line.split()
        if not p:
            continue
        if p[0] == "v":
            v.append([float(x) for x in p[1:4]])
        elif p[0] == "f":
            idx = [int(q.split("/")[0]) - 1 for q in p[1:]]
            for k in range(1, len(idx) - 1):
                f.append((idx[0], idx[k], idx[k + 1]))
    return np.array(v), np.array(f), None


def _material(shape):
    bsdf = shape.find("bsdf")
    if bsdf is None:
        raise SceneError(f"shape {shape.get('type')} has no bsdf")
    if bsdf.get("type") == "twosided":
        bsdf = bsdf.find("bsdf")
    kind = bsdf.get("type")
    if kind == "diffuse":
        return {"type": "diffuse", "reflectance": _rgb(bsdf, "reflectance")}
    if kind == "dielectric":
        return {"type": "dielectric", "int_ior": _float(bsdf, "int_ior"),
                "ext_ior": _float(bsdf, "ext_ior", 1.0)}
    if kind == "conductor":
        return {"type": "mirror", "reflectance": _rgb(bsdf, "specular_reflectance", [1, 1, 1])}
    raise SceneError(f"bsdf {kind!r}: not in the subset the peers' ports read")


def read(path):
    """Returns the scene of Mitsuba XML `path`: {camera, shapes}, each shape with world-space
    vertices, triangles (outward winding), vertex normals or None, a material and a radiance
    (or None)."""
    root = ET.parse(path).getroot()
    sensor = root.find("sensor")
    if sensor is None or sensor.get("type") != "perspective":
        raise SceneError("no perspective sensor")
    look = sensor.find("transform/lookat")
    film = sensor.find("film")
    ints = {c.get("name"): int(c.get("value")) for c in film if c.tag == "integer"}
    camera = {
        "origin": _floats(look.get("origin")),
        "target": _floats(look.get("target")),
        "up": _floats(look.get("up")),
        "fov_y": _float(sensor, "fov"),
        "width": ints["width"],
        "height": ints["height"],
    }
    axis = [c.get("value") for c in sensor if c.get("name") == "fov_axis"]
    if axis and axis[0] != "y":
        raise SceneError(f"fov_axis {axis[0]!r}: only y is read")
    if root.find("medium") is not None or root.find(".//medium") is not None:
        raise SceneError("participating media: not in the subset the peers' ports read")
    shapes = []
    for s in root.findall("shape"):
        kind = s.get("type")
        if kind == "cube":
            v, f, n = _cube()
        elif kind == "rectangle":
            v, f, n = _rectangle()
        elif kind == "sphere":
            centre = _floats(s.find("point").get("value"))
            v, f, n = _sphere(centre, _float(s, "radius"))
        elif kind == "obj":
            name = [c.get("value") for c in s if c.get("name") == "filename"][0]
            v, f, n = _obj(os.path.join(os.path.dirname(path), name))
        else:
            raise SceneError(f"shape {kind!r}: not in the subset the peers' ports read")
        if kind != "sphere":
            m = _to_world(s)
            v, n = _transform(m, v, n)
            if np.linalg.det(m[:3, :3]) < 0:
                f = f[:, ::-1]
        emitter = s.find("emitter")
        radiance = None
        if emitter is not None:
            if emitter.get("type") != "area":
                raise SceneError(f"emitter {emitter.get('type')!r}: only area emitters are read")
            radiance = _rgb(emitter, "radiance")
        shapes.append({"vertices": v, "faces": f, "normals": n,
                       "material": _material(s), "radiance": radiance})
    if root.find("emitter") is not None:
        raise SceneError("a scene-level emitter: only area emitters on shapes are read")
    return {"camera": camera, "shapes": shapes}



def arguments(flag, choices, argv=None):
    """The peers' renderers' command line: SCENE.xml OUT.exr, `flag` (the engine or mode) among
    `choices`, --seconds and --seed."""
    ap = argparse.ArgumentParser()
    ap.add_argument("xml")
    ap.add_argument("out")
    ap.add_argument(flag, choices=choices, required=True)
    ap.add_argument("--seconds", type=float, required=True)
    ap.add_argument("--seed", type=int, default=1)
    return ap.parse_args(argv)


def cpu():
    """This process's user and system CPU seconds so far, every thread's."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime
