# SPDX-License-Identifier: Apache-2.0
"""envpis scene files read the way envpis reads them (docs/scene-format.md), pure Python: no bpy, no numpy.

Shared by scripts/cycles_assets_scene.py (inside Blender: builds the Cycles scene) and
scripts/cycles_assets.py (outside: object masks), and tested without Blender by
tests/test_cycles_assets.py. The conventions are render/scene_file.cpp's and render/gltf.cpp's:
- comments // and /* */ are allowed outside strings;
- ${ASSIMP_MODELS}, ${ENVPIS_ASSETS}, ${BLENDER_WORLDS} expand as scripts/assets-bench.sh and envpis do;
  relative file names are relative to the scene file;
- an object's transform is scale, then rotation (degrees about X, then Y, then Z: R = Rz Ry Rx), then
  translation; a glTF file is turned from +Y up to +Z up, (x, y, z) -> (x, -z, y), before it;
- a conductor's "roughness" is the GGX alpha; a pbr material's alpha is roughness^2.
"""
import ctypes
import json
import math
import os
import struct

BLENDER_WORLDS = "/usr/share/blender/datafiles/studiolights/world"


class SceneError(Exception):
    pass


def strip_comments(text):
    """The JSON text without // and /* */ comments (kept inside strings, where paths live)."""
    out, i, n, in_string = [], 0, len(text), False
    while i < n:
        c = text[i]
        if in_string:
            out.append(c)
            if c == "\\" and i + 1 < n:
                out.append(text[i + 1])
                i += 1
            elif c == '"':
                in_string = False
        elif c == '"':
            in_string = True
            out.append(c)
        elif text.startswith("//", i):
            while i < n and text[i] != "\n":
                i += 1
            continue
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            if end < 0:
                raise SceneError("unterminated /* comment")
            i = end + 2
            continue
        else:
            out.append(c)
        i += 1
    return "".join(out)


def directory_variables(environ=None):
    """The directories of ${...} in file names, with envpis's defaults (docs/scene-format.md)."""
    env = os.environ if environ is None else environ
    cache = env.get("XDG_CACHE_HOME") or os.path.join(env.get("HOME", "/"), ".cache")
    return {"ASSIMP_MODELS": env.get("ENVPIS_ASSIMP_MODELS") or "/usr/share/assimp/models",
            "ENVPIS_ASSETS": env.get("ENVPIS_ASSETS") or os.path.join(cache, "envpis", "assets"),
            "BLENDER_WORLDS": BLENDER_WORLDS}


def expand_path(name, scene_dir, variables):
    """A scene file's file name -> an absolute path (variables expanded, then relative to the scene)."""
    out = name
    while "${" in out:
        start = out.index("${")
        end = out.find("}", start)
        if end < 0:
            raise SceneError("'%s': unterminated ${" % name)
        var = out[start + 2:end]
        if var not in variables:
            raise SceneError("'%s': unknown variable ${%s}" % (name, var))
        out = out[:start] + variables[var] + out[end + 1:]
    return os.path.normpath(os.path.join(scene_dir, out))


def load_scene(path, environ=None):
    """The scene file as a dict, every file name (objects' and textures') made absolute."""
    try:
        with open(path) as f:
            scene = json.loads(strip_comments(f.read()))
    except OSError as e:
        raise SceneError("cannot read the scene '%s': %s" % (path, e.strerror))
    except ValueError as e:
        raise SceneError("'%s': not JSON: %s" % (path, e))
    if not isinstance(scene, dict) or not isinstance(scene.get("objects"), list) or not scene["objects"]:
        raise SceneError("'%s': no objects" % path)
    variables = directory_variables(environ)
    d = os.path.dirname(os.path.abspath(path))

    def fix(node):
        if isinstance(node, dict):
            for k, v in node.items():
                if k == "file" and isinstance(v, str):
                    node[k] = expand_path(v, d, variables)
                elif k.endswith("_texture") and isinstance(v, str):
                    node[k] = {"file": expand_path(v, d, variables)}
                else:
                    fix(v)
        elif isinstance(node, list):
            for v in node:
                fix(v)
    fix(scene)
    return scene


# ---- transforms ----

def rotation_xyz(degrees):
    """R = Rz Ry Rx (render/scene_file.cpp euler_xyz) as 3 rows; also Blender's XYZ Euler order."""
    def rot(axis, deg):
        a = math.radians(deg)
        c, s = math.cos(a), math.sin(a)
        r = [[1.0 if i == j else 0.0 for j in range(3)] for i in range(3)]
        i, j = (axis + 1) % 3, (axis + 2) % 3
        r[i][i], r[i][j], r[j][i], r[j][j] = c, -s, s, c
        return r

    def mul(a, b):
        return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    return mul(rot(2, degrees[2]), mul(rot(1, degrees[1]), rot(0, degrees[0])))


def object_transform(obj):
    """(scale [3], rotate degrees [3], translate [3]) of a mesh, quad or gltf object."""
    s = obj.get("scale", 1.0)
    scale = [float(s)] * 3 if isinstance(s, (int, float)) else [float(v) for v in s]
    return scale, [float(v) for v in obj.get("rotate", [0, 0, 0])], [float(v) for v in obj.get("translate", [0, 0, 0])]


def y_up_to_z_up(p):
    """glTF's +Y up to envpis's (and Blender's) +Z up (render/gltf.cpp)."""
    return (p[0], -p[2], p[1])


def look_at_basis(eye, target, up):
    """(right, true up, forward) unit vectors of envpis's camera (render/camera.h): right = forward x up."""
    def sub(a, b):
        return [a[i] - b[i] for i in range(3)]

    def cross(a, b):
        return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]

    def unit(a):
        n = math.sqrt(sum(x * x for x in a))
        if n == 0:
            raise SceneError("camera: degenerate direction")
        return [x / n for x in a]
    forward = unit(sub(target, eye))
    right = unit(cross(forward, up))
    return right, cross(right, forward), forward


# ---- materials ----

def conductor_f0(eta, k):
    """Fresnel reflectance at normal incidence of a complex IOR eta + i k: ((n-1)^2 + k^2) / ((n+1)^2 + k^2)."""
    return [((n - 1) ** 2 + kk * kk) / ((n + 1) ** 2 + kk * kk) for n, kk in zip(eta, k)]


def colour(value, default):
    v = default if value is None else value
    return [float(v)] * 3 if isinstance(v, (int, float)) else [float(x) for x in v]


def cycles_roughness(alpha):
    """Cycles' roughness input for a GGX alpha: Cycles squares it. envpis clamps alpha to >= 1e-3."""
    return math.sqrt(max(alpha, 1e-3))


def texture_mapping(transform):
    """KHR_texture_transform (glTF UV, v = 0 at the image's top) -> a Blender Mapping node's (location,
    scale) on Blender's UV (V = 1 - v): u' = ox + su u, v' = oy + sv v gives V' = sv V + 1 - oy - sv.
    Rotation is not supported (none of the scenes uses it)."""
    if float(transform.get("rotation", 0)) != 0:
        raise SceneError("texture rotation is not supported by the Cycles scene")
    ox, oy = [float(v) for v in transform.get("offset", [0, 0, 0])][:2]
    su, sv = [float(v) for v in transform.get("scale", [1, 1, 1])][:2]
    return (ox, 1.0 - oy - sv, 0.0), (su, sv, 1.0)


# ---- object ids: the envpis meshes each scene object becomes ----

def gltf_json(path):
    """The JSON chunk of a .gltf or .glb file."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] == b"glTF":
        length, kind = struct.unpack("<I4s", data[12:20])
        if kind != b"JSON":
            raise SceneError("'%s': first GLB chunk is not JSON" % path)
        return json.loads(data[20:20 + length])
    return json.loads(data)


def uses_draco(path):
    """Whether the glTF's meshes are Draco-compressed (KHR_draco_mesh_compression)."""
    return "KHR_draco_mesh_compression" in gltf_json(path).get("extensionsUsed", [])


def without_draco(path, out_path):
    """Rewrites a Draco-compressed glTF as a plain .glb through the system's assimp (the library envpis
    reads glTF with): Debian's Blender 3.4 ships the glTF importer without its Draco decoder, so it
    cannot read @pmndrs' bunny and Suzanne. assimp keeps glTF's +Y up, so Blender's importer then
    converts exactly as it would the original. Returns out_path."""
    try:
        lib = ctypes.CDLL("libassimp.so.5")
    except OSError as e:
        raise SceneError("'%s' is Draco-compressed and libassimp.so.5 is missing (Debian libassimp5): %s"
                         % (path, e))
    lib.aiImportFile.restype = ctypes.c_void_p
    lib.aiImportFile.argtypes = [ctypes.c_char_p, ctypes.c_uint]
    lib.aiExportScene.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint]
    lib.aiReleaseImport.argtypes = [ctypes.c_void_p]
    lib.aiGetErrorString.restype = ctypes.c_char_p
    scene = lib.aiImportFile(path.encode(), 0)
    if not scene:
        raise SceneError("assimp cannot read '%s': %s" % (path, lib.aiGetErrorString().decode()))
    status = lib.aiExportScene(scene, b"glb2", out_path.encode(), 0)
    lib.aiReleaseImport(scene)
    if status != 0:
        raise SceneError("assimp cannot write '%s': %s" % (out_path, lib.aiGetErrorString().decode()))
    return out_path


def is_portal_node(name):
    """A glTF node that is a portal, not geometry (render/gltf.h, docs/scene-format.md)."""
    return (name or "").startswith("portal")


def gltf_material_count(path):
    """How many meshes envpis makes of a glTF object without a replacement material: one per material
    its instanced primitives use (a primitive without one uses a default material); portal nodes are
    not geometry."""
    j = gltf_json(path)
    meshes, used, seen = j.get("meshes", []), set(), set()
    nodes = j.get("nodes", [])
    roots = j["scenes"][j.get("scene", 0)]["nodes"] if j.get("scenes") else range(len(nodes))
    stack = list(roots)
    while stack:
        n = stack.pop()
        if n in seen:
            continue
        seen.add(n)
        node = nodes[n]
        if "mesh" in node and not is_portal_node(node.get("name")):
            for prim in meshes[node["mesh"]].get("primitives", []):
                if prim.get("mode", 4) == 4:
                    used.add(prim.get("material", -1))
        stack.extend(node.get("children", []))
    return len(used)


def object_id_groups(scene):
    """[(name, [envpis object ids])] per scene object, in envpis's id order (a gltf object without a
    "material" is one id per glTF material)."""
    groups, next_id = [], 0
    for i, obj in enumerate(scene["objects"]):
        n = 1
        if obj.get("type") == "gltf" and "material" not in obj:
            n = gltf_material_count(obj["file"])
        groups.append((obj.get("name") or "%s-%d" % (obj.get("type"), i), list(range(next_id, next_id + n))))
        next_id += n
    return groups
