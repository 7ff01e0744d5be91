"""Print what a .glb holds that matters to a renderer: nodes, cameras, lights, materials,
images and the file size. Standard library only (any python3):

    python3 tools/gltf_scenes/inspect_glb.py scenes/gltf/*.glb
"""

import json
import math
import os
import struct
import sys


def read_glb_json(path):
    with open(path, 'rb') as f:
        data = f.read()
    magic, version, length = struct.unpack_from('<4sII', data, 0)
    if magic != b'glTF' or version != 2 or length != len(data):
        raise ValueError(f'{path}: not a glTF 2 binary (magic {magic!r}, version {version}, length {length})')
    chunk_len, chunk_type = struct.unpack_from('<I4s', data, 12)
    if chunk_type != b'JSON':
        raise ValueError(f'{path}: first chunk is {chunk_type!r}, not JSON')
    return json.loads(data[20:20 + chunk_len])


def fmt(v):
    if isinstance(v, float):
        return f'{v:.4g}'
    if isinstance(v, list):
        return '[' + ', '.join(fmt(x) for x in v) + ']'
    if isinstance(v, dict):
        return '{' + ', '.join(f'{k}: {fmt(x)}' for k, x in v.items()) + '}'
    return str(v)


def inspect(path):
    g = read_glb_json(path)
    lights = g.get('extensions', {}).get('KHR_lights_punctual', {}).get('lights', [])
    print(f'== {os.path.basename(path)}: {os.path.getsize(path)} bytes, '
          f'extensionsUsed {g.get("extensionsUsed", [])}')
    print('  nodes:')
    for n in g.get('nodes', []):
        what = [f'mesh {g["meshes"][n["mesh"]]["name"]}' if 'mesh' in n else '',
                f'camera {n["camera"]}' if 'camera' in n else '',
                f'light {n["extensions"]["KHR_lights_punctual"]["light"]}'
                if 'KHR_lights_punctual' in n.get('extensions', {}) else '']
        trs = {k: n[k] for k in ('translation', 'rotation', 'scale') if k in n}
        print(f'    {n.get("name")}: {" ".join(w for w in what if w)} {fmt(trs)}'
              + (f' children {n["children"]}' if 'children' in n else ''))
    for i, c in enumerate(g.get('cameras', [])):
        p = c.get('perspective', {})
        print(f'  camera {i} {c.get("name")}: {c["type"]} yfov {p.get("yfov", 0):.4f} rad '
              f'({math.degrees(p.get("yfov", 0)):.2f} deg) aspectRatio {fmt(p.get("aspectRatio"))} '
              f'znear {fmt(p.get("znear"))} zfar {fmt(p.get("zfar"))}')
    for i, l in enumerate(lights):
        spot = l.get('spot')
        spot_s = ''
        if spot is not None:
            inner, outer = spot.get('innerConeAngle', 0.0), spot.get('outerConeAngle', math.pi / 4)
            spot_s = (f' inner {inner:.4f} ({math.degrees(inner):.2f} deg)'
                      f' outer {outer:.4f} ({math.degrees(outer):.2f} deg)')
        print(f'  light {i} {l.get("name")}: {l["type"]} color {fmt(l.get("color", [1, 1, 1]))} '
              f'intensity {fmt(l.get("intensity", 1.0))}{spot_s}'
              + (f' range {fmt(l["range"])}' if 'range' in l else ''))
    for i, m in enumerate(g.get('materials', [])):
        pbr = dict(m.get('pbrMetallicRoughness', {}))
        if 'baseColorTexture' in pbr:
            pbr['baseColorTexture'] = f'texture {pbr["baseColorTexture"]["index"]}'
        extra = {k: m[k] for k in ('emissiveFactor', 'doubleSided', 'alphaMode') if k in m}
        print(f'  material {i} {m.get("name")}: pbr {fmt(pbr)} {fmt(extra)}'
              + (f' ext {fmt(m["extensions"])}' if m.get('extensions') else ''))
    for i, t in enumerate(g.get('textures', [])):
        s = g['samplers'][t['sampler']] if 'sampler' in t else {}
        print(f'  texture {i}: source {t.get("source")} sampler {fmt(s)}')
    for i, im in enumerate(g.get('images', [])):
        where = f'bufferView {im["bufferView"]} ({g["bufferViews"][im["bufferView"]]["byteLength"]} bytes)' \
            if 'bufferView' in im else f'uri {im.get("uri")}'
        print(f'  image {i} {im.get("name")}: mimeType {im.get("mimeType")} {where}')
    tris = sum(g['accessors'][p['indices']]['count'] // 3 for m in g.get('meshes', []) for p in m['primitives'])
    print(f'  meshes {len(g.get("meshes", []))}, triangles {tris}')


if __name__ == '__main__':
    for p in sys.argv[1:]:
        inspect(p)
