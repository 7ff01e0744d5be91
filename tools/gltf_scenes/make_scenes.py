"""Small glTF (.glb) test scenes written by Blender's own glTF exporter.

They are for validating caustic's glTF scene import against Mitsuba 3 (tools/validate): each
scene is what a Blender user would typically make and export, so the files carry the
exporter's real conventions (Y-up, yfov from the render aspect, lights in photometric units,
emissive strength, transmission/IOR/volume extensions, embedded PNG images).

Every scene has a perspective camera (render resolution 320x240, so aspectRatio 4:3) aimed at
the subject, and all but spot_and_sun.glb sit in a closed 3 x 3 x 2.5 m room of white-ish
diffuse quads (Principled BSDF: base colour 0.7, roughness 1, metallic 0), lit by an emissive
quad just under the ceiling, facing down (black base colour, Emission Color white, Emission
Strength 10: written as emissiveFactor + KHR_materials_emissive_strength).

  glass_of_water.glb  a table (box) with a drinking glass (a closed lathed shell with 3 mm
                      walls; transmission 1, IOR 1.5, roughness 0) holding water (a lathed
                      cylinder, transmission 1, IOR 1.33, roughness 0), standing on the
                      table: 0.5 mm air gaps between table, glass and water, so no two
                      surfaces coincide. Both carry a glTF Material Output
                      thickness, so the exporter writes KHR_materials_volume (solid, refracting
                      volumes, not thin-walled). Also one Blender point light (10 W, radius 0),
                      to exercise KHR_lights_punctual "point" and give a visible caustic.
  copper_bowl.glb     a rough copper bowl (hemispherical shell; metallic 1, base colour
                      (0.955, 0.638, 0.538), roughness 0.35) on the floor.
  frosted_sphere.glb  a frosted glass sphere (UV sphere 32x16; transmission 1, IOR 1.5,
                      roughness 0.3, volume) on the floor.
  textured_box.glb    a box whose base colour is a 64x64 checker image generated here (tiles
                      ramp in brightness along u and v, so flips show), packed, so the GLB
                      embeds it as a PNG in a buffer view (sampler: nearest).
  spot_and_sun.glb    floor + back wall + box, no emitter: a Blender SPOT light (100 W,
                      spot_size 45 deg, blend 0.2) and a SUN light (strength 1 W/m^2), to
                      exercise the "spot" and "directional" punctual types.

Run (after tools/gltf_scenes/setup.sh), from the repository root:

    tools/gltf_scenes/.venv/bin/python tools/gltf_scenes/make_scenes.py [OUTDIR]

OUTDIR defaults to scenes/gltf in this repository. The output is deterministic: re-running rewrites identical files.
Units: metres; Blender is Z-up and the exporter converts to glTF's Y-up (export_yup=True).
"""

import math
import os
import sys
import time

import bpy
import bmesh
from mathutils import Matrix, Vector

ROOM_W, ROOM_D, ROOM_H = 3.0, 3.0, 2.5  # x, y (depth), z (height); floor at z = 0
WALL_GREY = (0.7, 0.7, 0.7)


# --------------------------------------------------------------------------- materials


def principled(name, base=(0.8, 0.8, 0.8), metallic=0.0, roughness=0.5, **inputs):
    """A material whose node tree is the default Principled BSDF -> Material Output."""
    mat = bpy.data.materials.new(name)
    nodes = mat.node_tree.nodes
    bsdf = next(n for n in nodes if n.type == 'BSDF_PRINCIPLED')
    bsdf.inputs['Base Color'].default_value = (*base, 1.0)
    bsdf.inputs['Metallic'].default_value = metallic
    bsdf.inputs['Roughness'].default_value = roughness
    for key, value in inputs.items():
        socket = bsdf.inputs[key.replace('_', ' ')]
        socket.default_value = (*value, 1.0) if isinstance(value, tuple) and len(value) == 3 else value
    mat.diffuse_color = (*base, 1.0)  # viewport colour only
    return mat


def diffuse_white():
    return principled('wall_diffuse', base=WALL_GREY, roughness=1.0)


def emitter_material(strength=10.0):
    mat = principled('ceiling_light_emission', base=(0.0, 0.0, 0.0), roughness=1.0,
                     Emission_Color=(1.0, 1.0, 1.0), Emission_Strength=strength)
    # One-sided: glTF doubleSided=false, so the quad is an area light facing down only.
    mat.use_backface_culling = True
    return mat


def glass_material(name, ior, roughness=0.0, thickness=0.0):
    """Clear (or frosted) dielectric. With thickness > 0 a 'glTF Material Output' group
    (the node group the glTF add-on itself creates) carries it, so the exporter writes
    KHR_materials_volume: without it a glTF transmissive surface is thin-walled."""
    mat = principled(name, base=(1.0, 1.0, 1.0), roughness=roughness,
                     Transmission_Weight=1.0, IOR=ior)
    if thickness > 0.0:
        from io_scene_gltf2.blender.com.material_helpers import (
            create_settings_group, get_gltf_node_name)
        group = bpy.data.node_groups.get(get_gltf_node_name()) or create_settings_group(get_gltf_node_name())
        node = mat.node_tree.nodes.new('ShaderNodeGroup')
        node.node_tree = group
        node.location = (300, -300)
        node.inputs['Thickness'].default_value = thickness
    return mat


# --------------------------------------------------------------------------- meshes


def link(name, mesh, material=None, location=(0, 0, 0), rotation_z=0.0):
    if material is not None:
        mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    obj.location = location
    obj.rotation_euler = (0.0, 0.0, rotation_z)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def quad_mesh(name, corners):
    """One quad; the corners' winding (counter-clockwise seen from the front) sets its normal."""
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([Vector(c) for c in corners], [], [(0, 1, 2, 3)])
    mesh.update()
    return mesh


def bmesh_to_mesh(name, bm, smooth_angle=None):
    """Turn a BMesh into a Mesh in a canonical order, so that exports are byte-identical
    from run to run: bmesh operators (create_uvsphere, spin, remove_doubles) return faces in
    an order that varies between runs, and the exporter writes triangles in face order."""
    bmesh.ops.recalc_face_normals(bm, faces=bm.faces)
    uv_layer = bm.loops.layers.uv.active
    order = sorted(bm.verts, key=lambda v: tuple(round(c, 6) for c in v.co))
    index = {v: i for i, v in enumerate(order)}
    faces = []
    for f in bm.faces:
        loops = [(index[l.vert], tuple(l[uv_layer].uv) if uv_layer else None) for l in f.loops]
        start = min(range(len(loops)), key=lambda i: loops[i][0])  # keeps the winding
        faces.append(loops[start:] + loops[:start])
    faces.sort(key=lambda loops: [i for i, _ in loops])
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([v.co.copy() for v in order], [], [[i for i, _ in loops] for loops in faces])
    if uv_layer:
        uvs = mesh.uv_layers.new(name='UVMap')
        uvs.data.foreach_set('uv', [c for loops in faces for _, uv in loops for c in uv])
    bm.free()
    if smooth_angle is not None:
        bm = bmesh.new()
        bm.from_mesh(mesh)
        for f in bm.faces:
            f.smooth = True
        for e in bm.edges:
            if e.is_manifold and e.calc_face_angle(0.0) > smooth_angle:
                e.smooth = False  # sharp edge: split normals there
        bm.to_mesh(mesh)
        bm.free()
    mesh.validate()
    mesh.update()
    return mesh


def box_mesh(name, size, uvs=False):
    bm = bmesh.new()
    if uvs:
        bm.loops.layers.uv.new('UVMap')
    bmesh.ops.create_cube(bm, size=1.0, calc_uvs=uvs)
    bmesh.ops.scale(bm, vec=Vector(size), verts=bm.verts)
    return bmesh_to_mesh(name, bm)


def lathe_mesh(name, profile, segments=32, smooth_angle=math.radians(40)):
    """Revolve a closed (r, z) profile about Z. Points with r == 0 become poles."""
    bm = bmesh.new()
    verts = [bm.verts.new((r, 0.0, z)) for r, z in profile]
    edges = [bm.edges.new((verts[i], verts[i + 1])) for i in range(len(verts) - 1)]
    bmesh.ops.spin(bm, geom=verts + edges, cent=(0, 0, 0), axis=(0, 0, 1),
                   angle=2 * math.pi, steps=segments, use_merge=True)
    bmesh.ops.remove_doubles(bm, verts=bm.verts, dist=1e-6)
    bmesh.ops.dissolve_degenerate(bm, edges=bm.edges, dist=1e-7)
    return bmesh_to_mesh(name, bm, smooth_angle)


def uv_sphere_mesh(name, radius, segments=32, rings=16):
    bm = bmesh.new()
    bm.loops.layers.uv.new('UVMap')
    bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=rings, radius=radius, calc_uvs=True)
    return bmesh_to_mesh(name, bm, smooth_angle=math.pi)


# --------------------------------------------------------------------------- scene parts


def add_room(closed=True, emitter_size=0.6, emission=10.0):
    """Closed room of inward-facing quads (or only floor + back wall) and a ceiling emitter."""
    wall = diffuse_white()
    x0, x1 = -ROOM_W / 2, ROOM_W / 2
    y0, y1 = -ROOM_D / 2, ROOM_D / 2
    z0, z1 = 0.0, ROOM_H
    walls = {
        'floor': [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)],
        'back_wall': [(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)],
    }
    if closed:
        walls.update({
            'ceiling': [(x0, y0, z1), (x0, y1, z1), (x1, y1, z1), (x1, y0, z1)],
            'left_wall': [(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)],
            'right_wall': [(x1, y0, z0), (x1, y0, z1), (x1, y1, z1), (x1, y1, z0)],
            'front_wall': [(x0, y0, z0), (x0, y0, z1), (x1, y0, z1), (x1, y0, z0)],
        })
    for name, corners in walls.items():
        link(name, quad_mesh(name, corners), wall)
    if emission > 0.0:
        h = emitter_size / 2
        z = ROOM_H - 0.001  # just under the ceiling, facing down (-Z)
        corners = [(-h, -h, z), (-h, h, z), (h, h, z), (h, -h, z)]
        link('ceiling_light', quad_mesh('ceiling_light', corners), emitter_material(emission))


def look_at(obj, target):
    direction = Vector(target) - obj.location
    obj.rotation_euler = direction.to_track_quat('-Z', 'Y').to_euler()


def add_camera(location, target, lens_mm=35.0):
    cam = bpy.data.cameras.new('camera')
    cam.type = 'PERSP'
    cam.lens = lens_mm
    cam.sensor_fit = 'AUTO'  # 36 mm across the wider (horizontal) side
    cam.clip_start = 0.05
    cam.clip_end = 100.0
    obj = bpy.data.objects.new('camera', cam)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    look_at(obj, target)
    scene = bpy.context.scene
    scene.camera = obj
    scene.render.resolution_x = 320
    scene.render.resolution_y = 240
    scene.render.resolution_percentage = 100
    scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0
    return obj


def add_light(name, kind, location, target=None, **props):
    light = bpy.data.lights.new(name, kind)
    light.color = (1.0, 1.0, 1.0)
    if kind in ('POINT', 'SPOT'):
        light.shadow_soft_size = 0.0  # glTF punctual lights have no radius
    for key, value in props.items():
        setattr(light, key, value)
    obj = bpy.data.objects.new(name, light)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    if target is not None:
        look_at(obj, target)  # lights shine along their local -Z
    return obj


# --------------------------------------------------------------------------- scenes


def scene_glass_of_water():
    add_room()
    table_h = 0.7
    link('table', box_mesh('table', (1.0, 0.6, table_h)),
         principled('table_wood', base=(0.45, 0.3, 0.18), roughness=0.6), location=(0, 0, table_h / 2))
    # Glass: closed shell revolved from its cross-section (outer wall, rim, inner wall, base).
    R, H, wall, base = 0.045, 0.13, 0.003, 0.008
    glass_profile = [(0.0, 0.0), (R, 0.0), (R, H), (R - wall, H), (R - wall, base), (0.0, base)]
    # An air gap under the glass and between glass and water: no two surfaces coincide. A glass
    # base lying exactly in the table's top is ill-posed (which of the two a ray meets first is
    # floating-point rounding), and renderers resolve it differently: 10-18% apart over the
    # base's pixels, which is no error of either.
    gap = 0.0005
    link('drinking_glass', lathe_mesh('drinking_glass', glass_profile),
         glass_material('glass', ior=1.5, thickness=wall), location=(0, 0, table_h + gap))
    r_w, z_w0, z_w1 = R - wall - gap, base + gap, 0.09
    water_profile = [(0.0, z_w0), (r_w, z_w0), (r_w, z_w1), (0.0, z_w1)]
    link('water', lathe_mesh('water', water_profile),
         glass_material('water', ior=1.33, thickness=2 * r_w), location=(0, 0, table_h + gap))
    add_light('point_light', 'POINT', (0.4, -0.3, 1.6), energy=10.0)
    add_camera((0.0, -0.55, 0.86), (0.0, 0.0, table_h + 0.055), lens_mm=50.0)


def scene_copper_bowl():
    add_room()
    R, t, n = 0.25, 0.015, 8  # outer radius, wall thickness, profile steps per quarter arc
    outer = [(R * math.sin(a), -R * math.cos(a)) for a in (i * math.pi / 2 / n for i in range(n + 1))]
    inner = [((R - t) * math.sin(a), -(R - t) * math.cos(a)) for a in (i * math.pi / 2 / n for i in range(n, -1, -1))]
    bowl = lathe_mesh('copper_bowl', outer + inner, smooth_angle=math.radians(60))
    copper = principled('copper', base=(0.955, 0.638, 0.538), metallic=1.0, roughness=0.35)
    link('copper_bowl', bowl, copper, location=(0, 0, R))
    add_camera((0.0, -1.3, 1.0), (0.0, 0.0, 0.12), lens_mm=40.0)


def scene_frosted_sphere():
    add_room()
    r = 0.3
    link('frosted_sphere', uv_sphere_mesh('frosted_sphere', r),
         glass_material('frosted_glass', ior=1.5, roughness=0.3, thickness=2 * r), location=(0, 0, r))
    add_camera((0.0, -1.4, 0.9), (0.0, 0.0, 0.3), lens_mm=35.0)


def checker_image(name='checker_64', size=64, tiles=8):
    """8x8 checker of orange and blue tiles whose brightness ramps along u (orange) and
    v (blue), so a flipped or rotated texture lookup shows."""
    img = bpy.data.images.new(name, size, size, alpha=False)
    cell = size // tiles
    pixels = []
    for y in range(size):  # Blender's pixel rows go bottom (v = 0) to top
        for x in range(size):
            u, v = (x + 0.5) / size, (y + 0.5) / size
            if ((x // cell) + (y // cell)) % 2 == 0:
                pixels.extend((0.5 + 0.45 * u, 0.25 + 0.25 * u, 0.05, 1.0))
            else:
                pixels.extend((0.05, 0.15 + 0.2 * v, 0.4 + 0.5 * v, 1.0))
    img.pixels.foreach_set(pixels)  # values are the sRGB-encoded bytes / 255
    img.update()
    img.pack()  # stored as PNG inside the .blend; the exporter embeds it in the GLB
    return img


def scene_textured_box():
    add_room()
    mat = principled('checker_box', roughness=1.0)
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    tex = nodes.new('ShaderNodeTexImage')
    tex.name = tex.label = 'checker_texture'
    tex.image = checker_image()
    tex.interpolation = 'Closest'
    tex.location = (-400, 200)
    bsdf = next(n for n in nodes if n.type == 'BSDF_PRINCIPLED')
    links.new(tex.outputs['Color'], bsdf.inputs['Base Color'])
    s = 0.6
    link('checker_box', box_mesh('checker_box', (s, s, s), uvs=True), mat,
         location=(0, 0, s / 2), rotation_z=math.radians(30))
    # Inside the room: a camera in the front wall's plane is ill-posed (the wall at distance 0).
    add_camera((0.0, -1.45, 1.1), (0.0, 0.0, 0.3), lens_mm=35.0)


def scene_spot_and_sun():
    add_room(closed=False, emission=0.0)
    s = 0.6
    link('box', box_mesh('box', (s, s, s)), principled('box_diffuse', base=WALL_GREY, roughness=1.0),
         location=(0, 0, s / 2), rotation_z=math.radians(20))
    add_light('spot_light', 'SPOT', (1.2, -1.0, 2.2), target=(0.0, 0.0, 0.3), energy=100.0,
              spot_size=math.radians(45.0), spot_blend=0.2)
    add_light('sun_light', 'SUN', (-1.0, -1.0, 3.0), target=(0.3, 0.5, 0.0), energy=1.0)
    add_camera((0.0, -2.6, 1.3), (0.0, 0.0, 0.35), lens_mm=35.0)


SCENES = {
    'glass_of_water': scene_glass_of_water,
    'copper_bowl': scene_copper_bowl,
    'frosted_sphere': scene_frosted_sphere,
    'textured_box': scene_textured_box,
    'spot_and_sun': scene_spot_and_sun,
}


def export(path):
    bpy.ops.export_scene.gltf(
        filepath=path,
        export_format='GLB',
        export_cameras=True,
        export_lights=True,
        export_yup=True,
        export_apply=True,
        export_image_format='AUTO',  # generated/packed images -> PNG
        export_materials='EXPORT',
        export_animations=False,
        export_extras=False,
        export_import_convert_lighting_mode='SPEC',  # the default: cd / lx with 683 lm/W
        use_selection=False,
    )


def main():
    repo = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    out_dir = os.path.abspath(sys.argv[1]) if len(sys.argv) > 1 else os.path.join(repo, 'scenes', 'gltf')
    os.makedirs(out_dir, exist_ok=True)
    total = 0.0
    for name, build in SCENES.items():
        bpy.ops.wm.read_factory_settings(use_empty=True)
        build()
        path = os.path.join(out_dir, name + '.glb')
        start = time.perf_counter()
        export(path)
        took = time.perf_counter() - start
        total += took
        print(f'{path}: {os.path.getsize(path)} bytes, export {took:.2f} s')
    print(f'total export time {total:.2f} s')


if __name__ == '__main__':
    main()
