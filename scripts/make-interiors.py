#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Writes the interior rooms of issue 24 (docs/portals.md, "Interior rooms") as glTF 2.0 files:

  scripts/make-interiors.py [DIR]     (default: the asset cache, ${ENVPIS_ASSETS}/interiors)

  window-room.gltf   4 x 5 x 2.8 m, one window in the east wall (+X), a glossy copper sphere and a
                     plastic box on a diffuse wooden floor;
  glossy-room.gltf   window-room with glossy surfaces, as many real interiors have: satin-painted walls
                     and ceiling (roughness 0.5) and a polished floor (0.15);
  two-windows.gltf   6 x 4 x 2.8 m, a large window in the west wall (-X) and a small one in the south
                     wall (-Y), a polished floor, a silver sphere and a box; under the blender maps
                     sunrise and city (sun at azimuth 144 degrees) the sun comes in through the large one.

Coordinates below are the renderer's (+Z up, metres); the file is glTF's +Y up: (x, y, z) -> (x, z, -y),
the inverse of the turn envpis and Blender's importer apply. Every wall is a closed rectangle cut into
the grid of its openings (real holes, no overlaps); the rooms are closed except for the windows. Each
window carries a portal: a node named "portal-..." (docs/scene-format.md, "Portals in glTF") whose quad
fills the opening exactly, its front face (counter-clockwise winding) looking out of the room.
Deterministic: the same bytes on every run (stdlib only, fixed float formatting, sorted JSON).
"""
import base64
import json
import math
import os
import struct
import sys

WHITE = {"name": "wall", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.78, 1], "metallicFactor": 0.0,
                                                   "roughnessFactor": 1.0}, "doubleSided": True}


def material(name, color, metallic, roughness):
    return {"name": name, "doubleSided": True,
            "pbrMetallicRoughness": {"baseColorFactor": list(color) + [1], "metallicFactor": metallic,
                                     "roughnessFactor": roughness}}


def to_gltf(p):
    return (p[0], p[2], -p[1])


class Mesh:
    """Triangles of one material (or of a portal: material None), renderer coordinates."""

    def __init__(self, name, material_name=None):
        self.name, self.material = name, material_name
        self.positions, self.normals, self.indices = [], [], []

    def quad(self, a, b, c, d, normal):
        """a, b, c, d counter-clockwise seen from the side `normal` points to."""
        base = len(self.positions)
        self.positions += [a, b, c, d]
        self.normals += [normal] * 4
        self.indices += [base, base + 1, base + 2, base, base + 2, base + 3]


def wall(mesh, origin, u_axis, v_axis, size, openings, normal):
    """The rectangle origin + s u_axis + t v_axis, s in [0, size[0]], t in [0, size[1]], without the
    openings [(s0, s1, t0, t1)]: the grid of all their edges, every cell not inside an opening. Wound
    counter-clockwise seen from `normal` (into the room)."""
    ss = sorted({0.0, size[0]} | {x for o in openings for x in o[:2]})
    ts = sorted({0.0, size[1]} | {x for o in openings for x in o[2:]})
    flip = dot(cross(u_axis, v_axis), normal) < 0

    def at(s, t):
        return tuple(origin[i] + s * u_axis[i] + t * v_axis[i] for i in range(3))

    for s0, s1 in zip(ss, ss[1:]):
        for t0, t1 in zip(ts, ts[1:]):
            sm, tm = 0.5 * (s0 + s1), 0.5 * (t0 + t1)
            if any(o[0] < sm < o[1] and o[2] < tm < o[3] for o in openings):
                continue
            q = [at(s0, t0), at(s1, t0), at(s1, t1), at(s0, t1)]
            if flip:
                q = q[::-1]
            mesh.quad(*q, normal)


def portal(name, origin, u_axis, v_axis, opening, outward):
    """The portal quad filling `opening` of a wall, counter-clockwise seen from outside."""
    m = Mesh(name)
    s0, s1, t0, t1 = opening
    q = [tuple(origin[i] + s * u_axis[i] + t * v_axis[i] for i in range(3)) for s, t in
         ((s0, t0), (s1, t0), (s1, t1), (s0, t1))]
    if dot(cross(u_axis, v_axis), outward) < 0:
        q = q[::-1]
    m.quad(*q, outward)
    return m


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def box(mesh, lo, hi):
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    mesh.quad((x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1), (0, 0, 1))
    mesh.quad((x0, y0, z0), (x0, y1, z0), (x1, y1, z0), (x1, y0, z0), (0, 0, -1))
    mesh.quad((x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1), (1, 0, 0))
    mesh.quad((x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0), (-1, 0, 0))
    mesh.quad((x0, y1, z0), (x0, y1, z1), (x1, y1, z1), (x1, y1, z0), (0, 1, 0))
    mesh.quad((x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1), (0, -1, 0))


def sphere(mesh, center, radius, segments=64, rings=32):
    base = len(mesh.positions)
    for r in range(rings + 1):
        th = math.pi * r / rings
        for s in range(segments + 1):
            ph = 2 * math.pi * s / segments
            n = (math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th))
            mesh.positions.append(tuple(center[i] + radius * n[i] for i in range(3)))
            mesh.normals.append(n)
    row = segments + 1
    for r in range(rings):
        for s in range(segments):
            a, b = base + r * row + s, base + (r + 1) * row + s
            # counter-clockwise seen from outside (theta grows downwards, phi anticlockwise about +Z)
            if r > 0:
                mesh.indices += [a, b, a + 1]
            if r < rings - 1:
                mesh.indices += [a + 1, b, b + 1]


def room(size, openings):
    """Floor, ceiling and four walls of the box [-X/2, X/2] x [-Y/2, Y/2] x [0, Z]; openings maps a
    wall ('east' +X, 'west' -X, 'north' +Y, 'south' -Y) to its openings (s0, s1, t0, t1), s along the
    wall's u axis from its origin, t the height. Returns the meshes (walls, floor, ceiling) and portals."""
    X, Y, Z = size
    hx, hy = 0.5 * X, 0.5 * Y
    walls, floor, ceiling = Mesh("walls", "wall"), Mesh("floor", "floor"), Mesh("ceiling", "wall")
    floor.quad((-hx, -hy, 0), (hx, -hy, 0), (hx, hy, 0), (-hx, hy, 0), (0, 0, 1))
    ceiling.quad((-hx, -hy, Z), (-hx, hy, Z), (hx, hy, Z), (hx, -hy, Z), (0, 0, -1))
    frames = {  # origin, u axis, length, inward normal
        "east": ((hx, -hy, 0), (0, 1, 0), Y, (-1, 0, 0)),
        "west": ((-hx, -hy, 0), (0, 1, 0), Y, (1, 0, 0)),
        "north": ((-hx, hy, 0), (1, 0, 0), X, (0, -1, 0)),
        "south": ((-hx, -hy, 0), (1, 0, 0), X, (0, 1, 0)),
    }
    portals = []
    for name, (origin, u, length, inward) in frames.items():
        ops = openings.get(name, [])
        wall(walls, origin, u, (0, 0, 1), (length, Z), ops, inward)
        for k, o in enumerate(ops):
            outward = tuple(-c for c in inward)
            portals.append(portal("portal-%s-%d" % (name, k), origin, u, (0, 0, 1), o, outward))
    return [walls, floor, ceiling], portals


class Writer:
    """One glTF 2.0 document, its buffer embedded as a base64 data URI."""

    def __init__(self):
        self.buf = bytearray()
        self.j = {"asset": {"version": "2.0", "generator": "envpis scripts/make-interiors.py"},
                  "scene": 0, "scenes": [{"nodes": []}], "nodes": [], "meshes": [], "materials": [],
                  "accessors": [], "bufferViews": []}

    def view(self, data, target):
        while len(self.buf) % 4:
            self.buf.append(0)
        self.j["bufferViews"].append({"buffer": 0, "byteOffset": len(self.buf), "byteLength": len(data),
                                      "target": target})
        self.buf += data
        return len(self.j["bufferViews"]) - 1

    def accessor(self, values, vec3):
        if vec3:
            data = b"".join(struct.pack("<3f", *to_gltf(v)) for v in values)
            acc = {"componentType": 5126, "count": len(values), "type": "VEC3"}
            pts = [struct.unpack("<3f", struct.pack("<3f", *to_gltf(v))) for v in values]
            acc["min"] = [min(p[i] for p in pts) for i in range(3)]
            acc["max"] = [max(p[i] for p in pts) for i in range(3)]
            acc["bufferView"] = self.view(data, 34962)
        else:
            data = struct.pack("<%dI" % len(values), *values)
            acc = {"componentType": 5125, "count": len(values), "type": "SCALAR",
                   "bufferView": self.view(data, 34963)}
        self.j["accessors"].append(acc)
        return len(self.j["accessors"]) - 1

    def add(self, mesh, materials):
        prim = {"attributes": {"POSITION": self.accessor(mesh.positions, True),
                               "NORMAL": self.accessor(mesh.normals, True)},
                "indices": self.accessor(mesh.indices, False)}
        if mesh.material is not None:
            prim["material"] = [m["name"] for m in materials].index(mesh.material)
        self.j["meshes"].append({"name": mesh.name, "primitives": [prim]})
        self.j["nodes"].append({"name": mesh.name, "mesh": len(self.j["meshes"]) - 1})
        self.j["scenes"][0]["nodes"].append(len(self.j["nodes"]) - 1)

    def write(self, path, materials, meshes):
        self.j["materials"] = materials
        for m in meshes:
            self.add(m, materials)
        self.j["buffers"] = [{"byteLength": len(self.buf),
                              "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(self.buf)).decode()}]
        with open(path, "w") as f:
            json.dump(self.j, f, sort_keys=True, separators=(",", ":"))
            f.write("\n")


def window_room():
    """4 x 5 x 2.8 m; the east window y in [-0.7, 0.7], z in [0.9, 2.0]."""
    meshes, portals = room((4, 5, 2.8), {"east": [(1.8, 3.2, 0.9, 2.0)]})
    copper, blocks = Mesh("sphere", "copper"), Mesh("box", "plastic")
    sphere(copper, (0.3, 0.4, 0.45), 0.45)
    box(blocks, (-0.9, -0.6, 0), (-0.3, 0.0, 0.6))
    materials = [WHITE, material("floor", (0.45, 0.3, 0.18), 0.0, 0.9),
                 material("copper", (0.95, 0.64, 0.54), 1.0, 0.15),
                 material("plastic", (0.6, 0.08, 0.06), 0.0, 0.25)]
    return materials, meshes + [copper, blocks] + portals


def glossy_room():
    """window_room's geometry, its diffuse surfaces made glossy (the product's case: a glossy lobe at
    most vertices)."""
    materials, meshes = window_room()
    satin = material("wall", (0.8, 0.8, 0.78), 0.0, 0.5)
    satin["doubleSided"] = True
    return [satin, material("floor", (0.45, 0.3, 0.18), 0.0, 0.15)] + materials[2:], meshes


def two_windows():
    """6 x 4 x 2.8 m; the west window y in [-1.2, 1.2], z in [0.5, 2.3] (4.3 m^2), the south window
    x in [0.8, 1.6], z in [1.3, 2.0] (0.56 m^2)."""
    meshes, portals = room((6, 4, 2.8), {"west": [(0.8, 3.2, 0.5, 2.3)], "south": [(3.8, 4.6, 1.3, 2.0)]})
    silver, blocks = Mesh("sphere", "silver"), Mesh("box", "plastic")
    sphere(silver, (0.6, 0.4, 0.5), 0.5)
    box(blocks, (-1.2, 0.6, 0), (-0.4, 1.4, 0.7))
    materials = [WHITE, material("floor", (0.5, 0.35, 0.22), 0.0, 0.3),
                 material("silver", (0.95, 0.93, 0.88), 1.0, 0.2),
                 material("plastic", (0.1, 0.25, 0.6), 0.0, 0.3)]
    return materials, meshes + [silver, blocks] + portals


def main(argv):
    if len(argv) > 1 or (argv and argv[0].startswith("-")):
        print("usage: make-interiors.py [DIR]", file=sys.stderr)
        return 2
    if argv:
        out = argv[0]
    else:
        cache = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        out = os.path.join(os.environ.get("ENVPIS_ASSETS") or os.path.join(cache, "envpis", "assets"), "interiors")
    os.makedirs(out, exist_ok=True)
    for name, make in (("window-room", window_room), ("glossy-room", glossy_room), ("two-windows", two_windows)):
        materials, meshes = make()
        path = os.path.join(out, name + ".gltf")
        Writer().write(path, materials, meshes)
        print("make-interiors: wrote %s" % path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
