# SPDX-License-Identifier: Apache-2.0
# Runs inside Blender (bpy), driven by scripts/cycles_compare.py; see docs/cycles.md.
#
#   blender -b --factory-startup --python scripts/cycles_scene.py -- \
#       --map sunrise.exr --roughness 0.2 --size 256 --ortho-height 2.2 --threads 2 \
#       [--pattern PROGRESSIVE_MULTI_JITTER|SOBOL] [--max-bounces 0] \
#       --render 64:0:/tmp/c-64-0.exr [--render SPP:SEED:FILE.exr ...]
#
# Builds the matched sphere scene of the Cycles side-by-side in an empty (factory) scene and renders it
# once per --render with Cycles on the CPU, writing 32-bit float RGB OpenEXRs. Blender stores Cycles'
# own timings in each EXR's header (cycles.<view layer>.render_time, .synchronization_time,
# .total_time); the caller reads them there, so this script only renders.
#
# The scene (each setting is matched to `envpis render --integrator direct --env-filter nearest`):
# - a unit sphere at the origin. It is a point of radius 1 made by Geometry Nodes ("Mesh to Points"),
#   which Cycles intersects as an exact sphere with the exact normal; a mesh sphere would have a
#   polygonal outline and interpolated normals, and both change a glossy reflection.
# - its material: Glossy BSDF, GGX, colour 1 (no Fresnel term), roughness r (Cycles squares it: the
#   GGX alpha is r^2, envpis's "roughness").
# - an orthographic camera at (0, -10, 0) looking along +Y with +Z up, ortho scale = the film's height
#   (the image is square, so also its width).
# - the world: the map in an Environment Texture node (equirectangular, "Closest", i.e. the texel's own
#   value, piecewise constant), multiple importance sampled with a map resolution equal to the map's
#   width, so the importance table has one cell per texel as envpis's nearest look-up has.
# - direct light only: max bounces 0 (a lone convex sphere never sees itself, so any bounce limit gives
#   the same image; 0 still adds the MIS'd BSDF sample that reaches the world: its images are bitwise
#   equal to --max-bounces 1's, see docs/cycles.md).
# - box pixel filter one pixel wide, no adaptive sampling, no denoising, light threshold 0, no clamping,
#   Filter Glossy 0, no path guiding, film exposure 1, a fixed number of threads.
import os
import sys

import bpy


PROG = "cycles_scene.py"  # the prefix of error lines; a script importing this module sets its own


def fail(message):
    # One line, then a non-zero exit status that Blender passes on (sys.exit inside --python does).
    print(PROG + ": error: " + message, file=sys.stderr)
    sys.stderr.flush()
    sys.exit(1)


def parse_args(argv):
    args = {"map": None, "roughness": None, "size": 256, "ortho_height": 2.2, "threads": 2,
            "pattern": "PROGRESSIVE_MULTI_JITTER",
            "max_bounces": 0, "renders": []}
    it = iter(argv)
    for key in it:
        try:
            value = next(it)
        except StopIteration:
            fail(key + ": missing value")
        try:
            if key == "--map":
                args["map"] = value
            elif key == "--roughness":
                args["roughness"] = float(value)
            elif key == "--size":
                args["size"] = int(value)
            elif key == "--ortho-height":
                args["ortho_height"] = float(value)
            elif key == "--threads":
                args["threads"] = int(value)
            elif key == "--max-bounces":
                args["max_bounces"] = int(value)
            elif key == "--pattern":
                args["pattern"] = value
            elif key == "--render":
                spp, seed, path = value.split(":", 2)
                args["renders"].append((int(spp), int(seed), path))
            else:
                fail("unknown option " + key)
        except ValueError:
            fail("%s: bad value '%s'" % (key, value))
    if not args["map"] or not os.path.isfile(args["map"]):
        fail("--map: no such file '%s'" % args["map"])
    if args["roughness"] is None or not 0 <= args["roughness"] <= 1:
        fail("--roughness must be in [0, 1]")
    if not args["renders"]:
        fail("nothing to render (give --render SPP:SEED:FILE.exr)")
    if args["pattern"] not in ("PROGRESSIVE_MULTI_JITTER", "SOBOL"):
        fail("--pattern must be PROGRESSIVE_MULTI_JITTER or SOBOL")
    return args


def sphere(material, center=(0.0, 0.0, 0.0), radius=1.0, name="sphere"):
    # One vertex turned into a point of the radius: Cycles renders points as true spheres.
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(center)], [], [])
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    tree = bpy.data.node_groups.new(name + "_sphere", "GeometryNodeTree")
    tree.inputs.new("NodeSocketGeometry", "Geometry")
    tree.outputs.new("NodeSocketGeometry", "Geometry")
    group_in = tree.nodes.new("NodeGroupInput")
    group_out = tree.nodes.new("NodeGroupOutput")
    to_points = tree.nodes.new("GeometryNodeMeshToPoints")
    to_points.inputs["Radius"].default_value = radius
    set_material = tree.nodes.new("GeometryNodeSetMaterial")
    set_material.inputs["Material"].default_value = material
    tree.links.new(group_in.outputs[0], to_points.inputs["Mesh"])
    tree.links.new(to_points.outputs["Points"], set_material.inputs["Geometry"])
    tree.links.new(set_material.outputs[0], group_out.inputs[0])
    obj.modifiers.new(name + "_sphere", "NODES").node_group = tree
    return obj


def glossy(roughness):
    mat = bpy.data.materials.new("ggx")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.clear()
    bsdf = nodes.new("ShaderNodeBsdfGlossy")
    bsdf.distribution = "GGX"
    bsdf.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    out = nodes.new("ShaderNodeOutputMaterial")
    mat.node_tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    return mat


def camera(ortho_height):
    data = bpy.data.cameras.new("ortho")
    data.type = "ORTHO"
    data.ortho_scale = ortho_height  # Blender's ortho scale is the larger film side; the film is square
    data.clip_start = 0.1
    data.clip_end = 100.0
    obj = bpy.data.objects.new("camera", data)
    # A Blender camera looks along its local -Z with local +Y up; turning it +90 degrees about X makes
    # that +Y (forward) and +Z (up), so image right is +X: envpis's from (0, -10, 0) to the origin.
    obj.location = (0.0, -10.0, 0.0)
    obj.rotation_euler = (1.5707963267948966, 0.0, 0.0)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.scene.camera = obj


def world(path):
    w = bpy.data.worlds.new("environment")
    bpy.context.scene.world = w
    w.use_nodes = True
    nodes = w.node_tree.nodes
    nodes.clear()
    tex = nodes.new("ShaderNodeTexEnvironment")
    try:
        tex.image = bpy.data.images.load(os.path.abspath(path), check_existing=False)
    except RuntimeError as e:
        fail("cannot load the map '%s': %s" % (path, e))
    width = tex.image.size[0]
    if width <= 0:
        fail("cannot read the map '%s' (no pixels)" % path)
    tex.image.colorspace_settings.name = "Linear"  # an EXR's values are used as radiance, unchanged
    tex.interpolation = "Closest"
    tex.projection = "EQUIRECTANGULAR"
    background = nodes.new("ShaderNodeBackground")
    background.inputs["Strength"].default_value = 1.0
    out = nodes.new("ShaderNodeOutputWorld")
    w.node_tree.links.new(tex.outputs["Color"], background.inputs["Color"])
    w.node_tree.links.new(background.outputs["Background"], out.inputs["Surface"])
    w.cycles.sampling_method = "MANUAL"
    w.cycles.sample_map_resolution = width  # Cycles' table is width x width/2 cells: one per texel
    return width


def settings(size, threads, pattern, max_bounces, height=None):
    # height: the film's height when it is not square (scripts/cycles_assets_scene.py).
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    c = sc.cycles
    c.device = "CPU"
    c.feature_set = "SUPPORTED"
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.sampling_pattern = pattern
    c.light_sampling_threshold = 0.0
    c.max_bounces = max_bounces
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    if hasattr(c, "use_guiding"):
        c.use_guiding = False
    c.use_animated_seed = False
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.film_exposure = 1.0
    sc.render.film_transparent = False
    sc.render.use_persistent_data = False
    sc.render.threads_mode = "FIXED"
    sc.render.threads = threads
    sc.render.resolution_x = size
    sc.render.resolution_y = size if height is None else height
    sc.render.resolution_percentage = 100
    sc.render.pixel_aspect_x = 1.0
    sc.render.pixel_aspect_y = 1.0
    img = sc.render.image_settings
    img.file_format = "OPEN_EXR"
    img.color_mode = "RGB"
    img.color_depth = "32"
    img.exr_codec = "ZIP"
    sc.render.use_file_extension = False


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    args = parse_args(argv)
    for obj in list(bpy.data.objects):  # --factory-startup's cube, light and camera
        bpy.data.objects.remove(obj)
    sphere(glossy(args["roughness"]))
    camera(args["ortho_height"])
    width = world(args["map"])
    settings(args["size"], args["threads"], args["pattern"], args["max_bounces"])
    print("cycles_scene.py: map %s (%d texels wide), roughness %g, %dx%d, %d threads, pattern %s"
          % (args["map"], width, args["roughness"], args["size"], args["size"], args["threads"], args["pattern"]))
    render_all(args["renders"], "cycles_scene.py")


def render_all(renders, who):
    """Renders the scene once per (spp, seed, path), each written as an EXR at path."""
    sc = bpy.context.scene
    for spp, seed, path in renders:
        sc.cycles.samples = spp
        sc.cycles.seed = seed
        sc.render.filepath = os.path.abspath(path)
        bpy.ops.render.render(write_still=True)
        if not os.path.isfile(sc.render.filepath):
            fail("Blender did not write '%s'" % path)
        print("%s: wrote %s (%d spp, seed %d)" % (who, path, spp, seed))
        sys.stdout.flush()


if __name__ == "__main__":  # also imported by scripts/cycles_assets_scene.py for its building blocks
    try:
        main()
    except SystemExit:
        raise
    except Exception as e:  # any bpy failure: one line and a non-zero exit, not a Blender prompt
        fail("%s: %s" % (type(e).__name__, e))
