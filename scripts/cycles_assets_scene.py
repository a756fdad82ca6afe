# SPDX-License-Identifier: Apache-2.0
# Runs inside Blender (bpy), driven by scripts/cycles_assets.py; see docs/cycles.md, "The asset scenes".
#
#   blender -b --factory-startup --python-exit-code 1 --python scripts/cycles_assets_scene.py -- \
#       --scene scenes/assets-bunny.json --map sunrise.exr --width 128 --height 72 --max-depth 8 \
#       --threads 2 [--pattern PROGRESSIVE_MULTI_JITTER|SOBOL] \
#       --render 64:0:/tmp/c-64-0.exr [--render SPP:SEED:FILE.exr ...]
#
# Builds the Cycles counterpart of an envpis scene file and renders it once per --render (32-bit float
# RGB OpenEXR; Blender writes Cycles' timings into the header). What matches `envpis render --scene S
# --env MAP --env-filter nearest --integrator path --max-depth D`:
# - glTF objects through Blender's own importer (bpy.ops.import_scene.gltf), which turns +Y up into +Z
#   up as envpis does, (x, y, z) -> (x, -z, y); then the scene's scale, rotate (X, then Y, then Z) and
#   translate, through a parent empty: Blender's object matrix is T Rz Ry Rx S, envpis's order. A glTF
#   portal node (named "portal...") becomes Cycles' portal: a rectangular area light marked is_portal
#   over the same quad (portal_light), not geometry.
# - spheres as Geometry-Nodes points (Cycles intersects exact spheres, scripts/cycles_scene.py), except
#   transmissive ones: a fine smooth mesh, because a ray that starts inside a Cycles 3.x point does not
#   hit its far side (Cycles' point_intersect_test keeps the front root only: "Always back-face culling
#   for now"; read in Cycles' source, not measured here).
# - quads as a square of side "size" at z = 0 with UVs (u along +X, Blender's V along +Y: glTF's v = 0
#   at the +Y edge, as envpis's quad).
# - materials (envpis's alpha is Cycles' roughness squared): diffuse -> Diffuse BSDF, translucent ->
#   Translucent BSDF, dielectric -> Glass BSDF (GGX), conductor -> Principled metallic with base colour
#   f0 (from eta/k: the normal-incidence reflectance), coated-diffuse -> Principled plastic (specular
#   0.5 = F0 0.04, base colour the albedo), pbr -> Principled BSDF as Blender's glTF importer builds it
#   (textures through Image Texture nodes, bilinear, KHR_texture_transform as a Mapping node, normal
#   map through a Normal Map node). Every Principled node (also the importer's) uses single-scattering
#   GGX, as envpis. docs/cycles.md lists what still differs.
# - the perspective camera: envpis's "fov" is the vertical field of view (render/camera.h).
# - the world as scripts/cycles_scene.py (Closest, equirectangular, MIS with map resolution = width).
# - path tracing: envpis's --max-depth D counts surface vertices (D = 1 is direct light), Cycles counts
#   bounces after the first hit, so max bounces = D - 1 (every per-type limit too, so only the total
#   counts); caustics on, Filter Glossy 0, no clamping, no denoising or adaptive sampling, light
#   threshold 0, box filter 1 px, fixed threads.
import math
import os
import sys
import tempfile

import bpy
from mathutils import Matrix, Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cycles_scene as CS  # noqa: E402  (world, settings, the point sphere, fail)
import envpis_scene as ES  # noqa: E402  (the scene file read as envpis reads it; pure Python)

CS.PROG = "cycles_assets_scene.py"
fail = CS.fail


def parse_args(argv):
    a = {"scene": None, "map": None, "width": 128, "height": 72, "max_depth": 8, "threads": 2,
         "pattern": "PROGRESSIVE_MULTI_JITTER", "renders": []}
    ints = {"--width": "width", "--height": "height", "--max-depth": "max_depth", "--threads": "threads"}
    it = iter(argv)
    for key in it:
        value = next(it, None)
        if value is None:
            fail(key + ": missing value")
        try:
            if key in ints:
                a[ints[key]] = int(value)
            elif key in ("--scene", "--map", "--pattern"):
                a[key[2:]] = value
            elif key == "--render":
                spp, seed, path = value.split(":", 2)
                a["renders"].append((int(spp), int(seed), path))
            else:
                fail("unknown option " + key)
        except ValueError:
            fail("%s: bad value '%s'" % (key, value))
    for k in ("scene", "map"):
        if not a[k] or not os.path.isfile(a[k]):
            fail("--%s: no such file '%s'" % (k, a[k]))
    if a["max_depth"] < 1:
        fail("--max-depth must be at least 1")
    if not a["renders"]:
        fail("nothing to render (give --render SPP:SEED:FILE.exr)")
    return a


# ---- materials ----

def node_material(name):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    mat.node_tree.nodes.clear()
    out = mat.node_tree.nodes.new("ShaderNodeOutputMaterial")
    return mat, mat.node_tree, out


def principled(tree, out):
    p = tree.nodes.new("ShaderNodeBsdfPrincipled")
    p.distribution = "GGX"
    tree.links.new(p.outputs["BSDF"], out.inputs["Surface"])
    return p


def rgba(c):
    return (c[0], c[1], c[2], 1.0)


def image_node(tree, texture, data):
    """An Image Texture node of a pbr texture {"file", "offset", "scale", "wrap"}, bilinear, with the
    texture transform on the object's UV map."""
    tex = tree.nodes.new("ShaderNodeTexImage")
    try:
        tex.image = bpy.data.images.load(texture["file"], check_existing=True)
    except RuntimeError as e:
        fail("cannot load the texture '%s': %s" % (texture["file"], e))
    tex.image.colorspace_settings.name = "Non-Color" if data else "sRGB"
    tex.interpolation = "Linear"
    tex.extension = {"repeat": "REPEAT", "clamp": "EXTEND"}.get(texture.get("wrap", "repeat"), None) or \
        fail("texture wrap '%s' is not supported" % texture.get("wrap"))
    try:
        location, scale = ES.texture_mapping(texture)
    except ES.SceneError as e:
        fail(str(e))
    uv = tree.nodes.new("ShaderNodeTexCoord")
    mapping = tree.nodes.new("ShaderNodeMapping")
    mapping.vector_type = "POINT"
    mapping.inputs["Location"].default_value = location
    mapping.inputs["Scale"].default_value = scale
    tree.links.new(uv.outputs["UV"], mapping.inputs["Vector"])
    tree.links.new(mapping.outputs["Vector"], tex.inputs["Vector"])
    return tex


def times(tree, a_socket, factor):
    m = tree.nodes.new("ShaderNodeMath")
    m.operation = "MULTIPLY"
    tree.links.new(a_socket, m.inputs[0])
    m.inputs[1].default_value = factor
    return m.outputs[0]


def pbr(name, m):
    """glTF metallic-roughness as Blender's glTF importer maps it onto the Principled BSDF."""
    mat, tree, out = node_material(name)
    p = principled(tree, out)
    base = ES.colour(m.get("base_color"), 0.8)
    rough, metal = float(m.get("roughness", 0.5)), float(m.get("metallic", 0.0))
    ior = float(m.get("ior", 1.5))
    p.inputs["Base Color"].default_value = rgba(base)
    p.inputs["Metallic"].default_value = metal
    p.inputs["Roughness"].default_value = rough
    p.inputs["Specular"].default_value = ((ior - 1) / (ior + 1)) ** 2 / 0.08  # 0.5 <-> F0 0.04
    p.inputs["IOR"].default_value = ior
    p.inputs["Transmission"].default_value = float(m.get("transmission", 0.0))
    p.inputs["Clearcoat"].default_value = float(m.get("clearcoat", 0.0))
    p.inputs["Clearcoat Roughness"].default_value = float(m.get("clearcoat_roughness", 0.0))
    if "base_color_texture" in m:
        tex = image_node(tree, m["base_color_texture"], data=False)
        mix = tree.nodes.new("ShaderNodeMixRGB")
        mix.blend_type = "MULTIPLY"
        mix.inputs["Fac"].default_value = 1.0
        mix.inputs["Color2"].default_value = rgba(base)
        tree.links.new(tex.outputs["Color"], mix.inputs["Color1"])
        tree.links.new(mix.outputs["Color"], p.inputs["Base Color"])
    for key in ("metallic_roughness_texture", "roughness_texture"):
        if key in m:  # roughness in G, metallic in B (a roughness_texture's B is ignored)
            sep = tree.nodes.new("ShaderNodeSeparateColor")
            tree.links.new(image_node(tree, m[key], data=True).outputs["Color"], sep.inputs["Color"])
            tree.links.new(times(tree, sep.outputs["Green"], rough), p.inputs["Roughness"])
            if key == "metallic_roughness_texture":
                tree.links.new(times(tree, sep.outputs["Blue"], metal), p.inputs["Metallic"])
    if "normal_texture" in m:
        nm = tree.nodes.new("ShaderNodeNormalMap")
        nm.space = "TANGENT"
        nm.uv_map = "UVMap"
        nm.inputs["Strength"].default_value = float(m.get("normal_scale", 1.0))
        tree.links.new(image_node(tree, m["normal_texture"], data=True).outputs["Color"], nm.inputs["Color"])
        tree.links.new(nm.outputs["Normal"], p.inputs["Normal"])
    return mat


def simple(name, shader, colour_input, colour, roughness=None, ior=None):
    mat, tree, out = node_material(name)
    n = tree.nodes.new(shader)
    if roughness is not None:
        n.distribution = "GGX"
        n.inputs["Roughness"].default_value = roughness
    if ior is not None:
        n.inputs["IOR"].default_value = ior
    n.inputs[colour_input].default_value = rgba(colour)
    tree.links.new(n.outputs["BSDF"], out.inputs["Surface"])
    return mat


def material(name, m):
    """One envpis material (render/materials/*.cpp, render/pbr_material.h) as a Blender material."""
    t = m.get("type")
    if t in ("diffuse", "lambert"):
        return simple(name, "ShaderNodeBsdfDiffuse", "Color", ES.colour(m.get("albedo"), 0.8))
    if t == "translucent":
        return simple(name, "ShaderNodeBsdfTranslucent", "Color", ES.colour(m.get("transmittance"), 0.5))
    if t in ("dielectric", "glass"):
        return simple(name, "ShaderNodeBsdfGlass", "Color", ES.colour(m.get("tint"), 1.0),
                      ES.cycles_roughness(float(m.get("roughness", 0.0))), float(m.get("ior", 1.5)))
    if t == "conductor":
        f0 = ES.conductor_f0(m["eta"], m["k"]) if "eta" in m else ES.colour(m.get("reflectance"), 0.9)
        return pbr(name, {"base_color": f0, "metallic": 1.0,
                          "roughness": ES.cycles_roughness(float(m.get("roughness", 0.2)))})
    if t in ("coated-diffuse", "plastic"):
        return pbr(name, {"base_color": ES.colour(m.get("albedo"), 0.5), "metallic": 0.0, "ior": m.get("ior", 1.5),
                          "roughness": ES.cycles_roughness(float(m.get("roughness", 0.1)))})
    if t == "pbr":
        return pbr(name, m)
    fail("material '%s': type '%s' has no Cycles counterpart here" % (name, t))


def transmissive(m):
    return m is not None and (m.get("type") in ("dielectric", "glass", "translucent") or
                              float(m.get("transmission", 0)) > 0)


# ---- objects ----

def link(obj):
    bpy.context.scene.collection.objects.link(obj)
    return obj


def assign(obj, mat):
    obj.data.materials.clear()
    obj.data.materials.append(mat)


def parent_transform(name, obj_json):
    """An empty carrying the object's transform (T Rz Ry Rx S, render/scene_file.cpp's order)."""
    scale, rotate, translate = ES.object_transform(obj_json)
    empty = link(bpy.data.objects.new(name + "-transform", None))
    empty.location = translate
    empty.rotation_mode = "XYZ"
    empty.rotation_euler = [math.radians(v) for v in rotate]
    empty.scale = scale
    return empty


def numpy_aliases():
    # Debian's Blender 3.4 glTF importer still uses np.bool, which numpy 1.24 removed (AttributeError);
    # the alias is the builtin bool it always stood for.
    import numpy
    if "bool" not in numpy.__dict__:
        numpy.bool = bool


def gltf_object(name, o, mat):
    numpy_aliases()
    before = set(bpy.data.objects)
    path = o["file"]
    try:
        if ES.uses_draco(path):
            path = ES.without_draco(path, os.path.join(tempfile.mkdtemp(prefix="cyassets-"), name + ".glb"))
        bpy.ops.import_scene.gltf(filepath=path, import_shading="NORMALS", merge_vertices=False)
    except (RuntimeError, OSError, ValueError, ES.SceneError) as e:
        fail("cannot import '%s': %s" % (o["file"], e))
    new = [x for x in bpy.data.objects if x not in before]
    for x in [x for x in new if x.type in ("LIGHT", "CAMERA")]:  # envpis reads neither
        new.remove(x)
        bpy.data.objects.remove(x)
    bpy.context.view_layer.update()
    empty = parent_transform(name, o)
    for x in new:
        if x.parent is None:  # its matrix_basis (the converted node transform) now sits under the empty
            x.parent = empty
            x.matrix_parent_inverse = Matrix.Identity(4)
    bpy.context.view_layer.update()
    for x in [x for x in new if x.type == "MESH" and ES.is_portal_node(x.name)]:
        portal_light(x)
        new.remove(x)
        bpy.data.objects.remove(x)
    for x in new:
        if mat is not None and x.type == "MESH":
            for slot in range(max(1, len(x.data.materials))):
                if slot < len(x.data.materials):
                    x.data.materials[slot] = mat
                else:
                    x.data.materials.append(mat)


def portal_light(obj):
    """A glTF portal node (docs/scene-format.md, "Portals in glTF": a quad whose front face looks out of
    the room) as Cycles' portal: a rectangular area light with is_portal over the same quad, its
    emitting side (local -Z) looking into the room. Cycles' portals are rectangles: a quad that is not
    one (corners off by more than 1e-4 of its size) is refused."""
    w = obj.matrix_world
    pts = []
    for v in obj.data.vertices:
        p = w @ v.co
        if all((p - q).length > 1e-6 for q in pts):
            pts.append(p)
    if len(pts) != 4 or not obj.data.polygons:
        fail("portal '%s': not a quad (%d distinct vertices)" % (obj.name, len(pts)))
    out = (w.to_3x3().inverted().transposed() @ obj.data.polygons[0].normal).normalized()
    center = sum(pts, Vector()) / 4
    # The corners in order around the centre, counter-clockwise seen from outside.
    ref = (pts[0] - center).normalized()
    side = out.cross(ref)
    pts.sort(key=lambda p: math.atan2((p - center).dot(side), (p - center).dot(ref)))
    ex, ey = pts[1] - pts[0], pts[3] - pts[0]
    size = max(ex.length, ey.length)
    if abs(ex.dot(ey)) > 1e-4 * size * size or (pts[2] - pts[1] - ey).length > 1e-4 * size:
        fail("portal '%s': not a rectangle (Cycles' portals are rectangular area lights)" % obj.name)
    data = bpy.data.lights.new(obj.name, "AREA")
    data.shape = "RECTANGLE"
    data.size, data.size_y = ex.length, ey.length
    data.cycles.is_portal = True
    light = link(bpy.data.objects.new(obj.name, data))
    x = ex.normalized()
    y = out.cross(x)
    light.matrix_world = Matrix(((x[0], y[0], out[0], center[0]), (x[1], y[1], out[1], center[1]),
                                 (x[2], y[2], out[2], center[2]), (0, 0, 0, 1)))


def quad(name, size, mat, o):
    h = 0.5 * size
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([(-h, -h, 0), (h, -h, 0), (h, h, 0), (-h, h, 0)], [], [(0, 1, 2, 3)])
    uv = mesh.uv_layers.new(name="UVMap")
    for loop, (u, v) in zip(mesh.loops, [(0, 0), (1, 0), (1, 1), (0, 1)]):
        uv.data[loop.index].uv = (u, v)
    obj = link(bpy.data.objects.new(name, mesh))
    assign(obj, mat)
    obj.parent = parent_transform(name, o)


def mesh_sphere(name, center, radius, mat):
    """A smooth UV sphere fine enough that its outline and normals differ from the exact sphere's by
    well under a pixel at the scenes' sizes (512 x 256 segments)."""
    bpy.ops.mesh.primitive_uv_sphere_add(segments=512, ring_count=256, radius=radius, location=center)
    obj = bpy.context.active_object
    obj.name = name
    bpy.ops.object.shade_smooth()
    assign(obj, mat)


def build_objects(scene, materials):
    for i, o in enumerate(scene["objects"]):
        name = o.get("name") or "%s-%d" % (o.get("type"), i)
        mname = o.get("material")
        if mname is not None and mname not in materials:
            fail("objects[%d]: unknown material '%s'" % (i, mname))
        mat = materials.get(mname)
        t = o.get("type")
        if t == "sphere":
            if transmissive(scene["materials"][mname]):
                mesh_sphere(name, o["center"], float(o["radius"]), mat)
            else:
                CS.sphere(mat, o["center"], float(o["radius"]), name)
        elif t == "quad":
            quad(name, float(o.get("size", 10.0)), mat, o)
        elif t == "gltf":
            gltf_object(name, o, mat)
        else:
            fail("objects[%d]: type '%s' is not supported by the Cycles scene" % (i, t))


def ggx_everywhere():
    # The glTF importer's Principled nodes too: envpis's lobes are single-scattering GGX.
    for mat in bpy.data.materials:
        if mat.node_tree:
            for n in mat.node_tree.nodes:
                if n.bl_idname == "ShaderNodeBsdfPrincipled":
                    n.distribution = "GGX"


def camera(c):
    if c.get("type", "perspective") != "perspective":
        fail("camera: only the perspective camera is supported by the Cycles scene")
    data = bpy.data.cameras.new("camera")
    data.sensor_fit = "VERTICAL"  # envpis's fov is the vertical field of view (render/camera.h)
    data.angle_y = math.radians(float(c.get("fov", 40.0)))
    data.clip_start = 1e-3
    data.clip_end = 1e4
    obj = link(bpy.data.objects.new("camera", data))
    right, up, forward = ES.look_at_basis(c["from"], c["to"], c.get("up", [0, 0, 1]))
    # A Blender camera looks along its local -Z with +Y up and +X right.
    m = Matrix(((right[0], up[0], -forward[0], c["from"][0]), (right[1], up[1], -forward[1], c["from"][1]),
                (right[2], up[2], -forward[2], c["from"][2]), (0, 0, 0, 1)))
    obj.matrix_world = m
    bpy.context.scene.camera = obj


def build(a):
    try:
        scene = ES.load_scene(a["scene"])
    except ES.SceneError as e:
        fail(str(e))
    if "environment" in scene:
        fail("the scene's own environment is not supported: pass the map with --map")
    for obj in list(bpy.data.objects):  # --factory-startup's cube, light and camera
        bpy.data.objects.remove(obj)
    materials = {name: material(name, m) for name, m in scene.get("materials", {}).items()}
    build_objects(scene, materials)
    ggx_everywhere()
    camera(scene["camera"])
    width = CS.world(a["map"])
    d = a["max_depth"] - 1
    CS.settings(a["width"], a["threads"], a["pattern"], d, height=a["height"])
    c = bpy.context.scene.cycles
    for key in ("diffuse_bounces", "glossy_bounces", "transmission_bounces", "volume_bounces",
                "transparent_max_bounces"):
        setattr(c, key, d)
    c.caustics_reflective = True
    c.caustics_refractive = True
    return width


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    a = parse_args(argv)
    width = build(a)
    print("cycles_assets_scene.py: scene %s, map %s (%d texels wide), %dx%d, max bounces %d, %d threads"
          % (a["scene"], a["map"], width, a["width"], a["height"], a["max_depth"] - 1, a["threads"]))
    CS.render_all(a["renders"], "cycles_assets_scene.py")


if __name__ == "__main__":
    try:
        main()
    except SystemExit:
        raise
    except Exception as e:  # any bpy failure: one line and a non-zero exit, not a Blender prompt
        fail("%s: %s" % (type(e).__name__, e))
