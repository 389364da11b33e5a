#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
# plane_census: how much of a world's opaque area lies off the axis planes, and in how few planes.
#
#   bench/plane_census.py WORLD.glb
#
# Opaque triangles (material alphaMode OPAQUE or none) in world space, grouped by plane: the unit normal
# (sign fixed, rounded to 0.01) and the offset (rounded to 2 cm). A triangle whose normal is within 0.0001
# of an axis counts as axis-aligned. Prints JSON: the opaque and off-axis areas, and for thresholds of
# 1, 4, 16 and 64 m2 how many off-axis planes hold at least that much and what share of the off-axis area
# they hold: what occluders in any plane could cover with few planes. Pure Python (no numpy); a glb whose
# accessors are float positions and integer indices.
import json, struct, math, sys
from collections import defaultdict
path = sys.argv[1]
data = open(path, 'rb').read()
jlen = struct.unpack_from('<I', data, 12)[0]
gl = json.loads(data[20:20 + jlen])
bin_off = 20 + jlen + 8
def acc(i):
    a = gl['accessors'][i]; bv = gl['bufferViews'][a['bufferView']]
    off = bin_off + bv.get('byteOffset', 0) + a.get('byteOffset', 0)
    n = a['count']; t = a['type']; ct = a['componentType']
    comps = {'SCALAR': 1, 'VEC3': 3}[t]
    fmt = {5126: 'f', 5125: 'I', 5123: 'H', 5121: 'B'}[ct]
    size = struct.calcsize(fmt)
    stride = bv.get('byteStride', size * comps)
    return [struct.unpack_from('<' + fmt * comps, data, off + k * stride) for k in range(n)]
def mat_of(node):
    if 'matrix' in node: m = node['matrix']; return [[m[c*4+r] for c in range(4)] for r in range(4)]
    t = node.get('translation', [0,0,0]); s = node.get('scale', [1,1,1]); q = node.get('rotation', [0,0,0,1])
    x,y,z,w = q
    R = [[1-2*(y*y+z*z), 2*(x*y-z*w), 2*(x*z+y*w)],[2*(x*y+z*w), 1-2*(x*x+z*z), 2*(y*z-x*w)],[2*(x*z-y*w), 2*(y*z+x*w), 1-2*(x*x+y*y)]]
    return [[R[r][0]*s[0], R[r][1]*s[1], R[r][2]*s[2], t[r]] for r in range(3)] + [[0,0,0,1]]
def mul(a, b): return [[sum(a[r][k]*b[k][c] for k in range(4)) for c in range(4)] for r in range(4)]
tris = []
def walk(ni, M):
    node = gl['nodes'][ni]; M = mul(M, mat_of(node))
    if 'mesh' in node:
        for prim in gl['meshes'][node['mesh']]['primitives']:
            mat = gl['materials'][prim['material']] if 'material' in prim else {}
            if mat.get('alphaMode', 'OPAQUE') != 'OPAQUE': continue
            P = acc(prim['attributes']['POSITION'])
            P = [tuple(M[r][0]*p[0]+M[r][1]*p[1]+M[r][2]*p[2]+M[r][3] for r in range(3)) for p in P]
            I = [i[0] for i in acc(prim['indices'])] if 'indices' in prim else list(range(len(P)))
            for k in range(0, len(I) - 2, 3): tris.append((P[I[k]], P[I[k+1]], P[I[k+2]]))
    for c in node.get('children', []): walk(c, M)
I4 = [[1 if r == c else 0 for c in range(4)] for r in range(4)]
for n in gl['scenes'][gl.get('scene', 0)]['nodes']: walk(n, I4)
total = 0.0; off = 0.0
planes = defaultdict(float)
for a, b, c in tris:
    u = [b[i]-a[i] for i in range(3)]; v = [c[i]-a[i] for i in range(3)]
    n = [u[1]*v[2]-u[2]*v[1], u[2]*v[0]-u[0]*v[2], u[0]*v[1]-u[1]*v[0]]
    l = math.sqrt(sum(x*x for x in n))
    if l == 0: continue
    area = l / 2; total += area
    n = [x / l for x in n]
    if max(abs(x) for x in n) > 0.9999: continue
    off += area
    # plane key: normal to 0.01, offset to 2 cm, sign-normalized
    s = 1 if (n[0], n[1], n[2]) > (0, 0, 0) else -1
    n = [s * x for x in n]
    d = sum(n[i]*a[i] for i in range(3))
    planes[(round(n[0], 2), round(n[1], 2), round(n[2], 2), round(d / 0.02))] += area
big = sorted(planes.values(), reverse=True)
out = {"world": path, "triangles": len(tris), "opaque_area_m2": round(total, 1),
       "off_axis_area_m2": round(off, 1), "off_axis_share": round(off / max(total, 1e-9), 4),
       "off_axis_planes": len(planes), "planes_at_least": []}
for thr in [1, 4, 16, 64]:
    a = sum(x for x in big if x >= thr)
    out["planes_at_least"].append({"area_m2": thr, "planes": sum(1 for x in big if x >= thr),
                                   "share_of_off_axis": round(a / max(off, 1e-9), 4)})
print(json.dumps(out, indent=2))
