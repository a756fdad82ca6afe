# SPDX-License-Identifier: Apache-2.0
"""Unit test of the pure parts of the Cycles asset-scene side by side (scripts/cycles-assets.sh): the scene
file read as envpis reads it (scripts/envpis_scene.py: comments, variables, transform order, camera
basis, texture transform, object ids) and the per-object metrics of scripts/cycles_metrics.py (robust
relMSE, masks, efficiency, tables). Needs numpy, not Blender.

  python3 tests/test_cycles_assets.py      (ctest: cycles_assets; exit 77 = skipped without numpy)
"""
import json
import math
import os
import sys
import tempfile
import unittest

try:
    import numpy as np
except ImportError:
    print("test_cycles_assets: numpy is missing: skipped")
    sys.exit(77)

REPO = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
sys.path.insert(0, os.path.join(REPO, "scripts"))
import cycles_metrics as M  # noqa: E402
import envpis_scene as ES  # noqa: E402


def apply(r, v):
    return [sum(r[i][k] * v[k] for k in range(3)) for i in range(3)]


class SceneFile(unittest.TestCase):
    def test_comments_are_stripped_outside_strings(self):
        text = '// head\n{"a": "x//y", /* b */ "c": [1, /* 2 */ 3]} // tail'
        self.assertEqual(json.loads(ES.strip_comments(text)), {"a": "x//y", "c": [1, 3]})
        with self.assertRaises(ES.SceneError):
            ES.strip_comments('{"a": 1 /* open')

    def test_variables_expand_as_envpis(self):
        v = ES.directory_variables({"HOME": "/h"})
        self.assertEqual(v["ENVPIS_ASSETS"], "/h/.cache/envpis/assets")
        self.assertEqual(v["ASSIMP_MODELS"], "/usr/share/assimp/models")
        v = ES.directory_variables({"HOME": "/h", "XDG_CACHE_HOME": "/c", "ENVPIS_ASSIMP_MODELS": "/m"})
        self.assertEqual((v["ENVPIS_ASSETS"], v["ASSIMP_MODELS"]), ("/c/envpis/assets", "/m"))
        self.assertEqual(ES.expand_path("${ASSIMP_MODELS}/a.glb", "/s", v), "/m/a.glb")
        self.assertEqual(ES.expand_path("b/c.png", "/s", v), "/s/b/c.png")
        with self.assertRaises(ES.SceneError):
            ES.expand_path("${NOPE}/x", "/s", v)

    def test_repository_scenes_load(self):
        for name in ("bunny", "clearcoat", "engine"):
            s = ES.load_scene(os.path.join(REPO, "scenes", "assets-%s.json" % name), {"HOME": "/h"})
            for o in s["objects"]:
                if "file" in o:
                    self.assertTrue(os.path.isabs(o["file"]) and "${" not in o["file"], o["file"])
        floor = ES.load_scene(os.path.join(REPO, "scenes", "assets-bunny.json"), {"HOME": "/h"})["materials"]["floor"]
        self.assertEqual(floor["normal_texture"]["file"], "/h/.cache/envpis/assets/normals/0000.webp")

    def test_rotation_is_x_then_y_then_z(self):
        # Rz Ry Rx: +X turned 90 about X stays +X, then 90 about Z becomes +Y (the other order gives +Z).
        r = ES.rotation_xyz([90, 0, 90])
        for got, want in zip(apply(r, [1, 0, 0]), [0, 1, 0]):
            self.assertAlmostEqual(got, want, places=6)
        # [90, 0, 0] turns a Y-up model Z-up: +Y -> +Z, as glTF's (x, y, z) -> (x, -z, y) does.
        for got, want in zip(apply(ES.rotation_xyz([90, 0, 0]), [0, 1, 0]), ES.y_up_to_z_up([0, 1, 0])):
            self.assertAlmostEqual(got, want, places=6)

    def test_transform_defaults(self):
        self.assertEqual(ES.object_transform({"scale": 2}), ([2.0] * 3, [0.0] * 3, [0.0] * 3))
        self.assertEqual(ES.object_transform({"scale": [1, 2, 3], "translate": [4, 5, 6]})[::2],
                         ([1.0, 2.0, 3.0], [4.0, 5.0, 6.0]))

    def test_camera_basis(self):
        right, up, forward = ES.look_at_basis([0, -10, 0], [0, 0, 0], [0, 0, 1])
        for v, w in ((right, [1, 0, 0]), (up, [0, 0, 1]), (forward, [0, 1, 0])):
            for a, b in zip(v, w):
                self.assertAlmostEqual(a, b, places=6)

    def test_materials(self):
        self.assertEqual(ES.conductor_f0([1.0], [0.0]), [0.0])
        self.assertAlmostEqual(ES.conductor_f0([1.5], [0.0])[0], 0.04)
        self.assertAlmostEqual(ES.cycles_roughness(0.25), 0.5)
        self.assertAlmostEqual(ES.cycles_roughness(0.0), math.sqrt(1e-3))
        self.assertEqual(ES.colour(0.4, 0.8), [0.4] * 3)

    def test_texture_transform_on_blender_uv(self):
        loc, scale = ES.texture_mapping({"scale": [3, 3, 0], "offset": [0.25, 0.5, 0]})
        # glTF v = 1 - V; u' = 0.25 + 3u, v' = 0.5 + 3v; Blender samples at V' = 1 - v'.
        for u, V in ((0.1, 0.2), (0.7, 0.9)):
            self.assertAlmostEqual(scale[0] * u + loc[0], 0.25 + 3 * u)
            self.assertAlmostEqual(scale[1] * V + loc[1], 1 - (0.5 + 3 * (1 - V)))
        with self.assertRaises(ES.SceneError):
            ES.texture_mapping({"rotation": 10})

    def test_object_ids_follow_gltf_materials(self):
        gltf = {"scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "children": [1]}, {"mesh": 1}],
                "meshes": [{"primitives": [{"material": 0}, {"material": 1}]},
                           {"primitives": [{"material": 1}, {}, {"material": 2, "mode": 1}]}]}
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "m.gltf")
            with open(path, "w") as f:
                json.dump(gltf, f)
            self.assertEqual(ES.gltf_material_count(path), 3)  # 0, 1 and the default; lines don't count
            self.assertFalse(ES.uses_draco(path))
            scene = {"objects": [{"type": "sphere", "name": "s"}, {"type": "gltf", "name": "g", "file": path},
                                 {"type": "gltf", "file": path, "material": "x"}, {"type": "quad"}]}
            self.assertEqual(ES.object_id_groups(scene),
                             [("s", [0]), ("g", [1, 2, 3]), ("gltf-2", [4]), ("quad-3", [5])])

    def test_portal_nodes_are_not_geometry(self):
        # A node named portal* is a portal quad for envpis (render/gltf.h), not a mesh with an object id.
        gltf = {"scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
                "nodes": [{"name": "walls", "mesh": 0}, {"name": "portal-east-0", "mesh": 1},
                          {"name": "portals-not", "mesh": 2}],
                "meshes": [{"primitives": [{"material": 0}]}, {"primitives": [{}]}, {"primitives": [{"material": 1}]}]}
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "room.gltf")
            with open(path, "w") as f:
                json.dump(gltf, f)
            # "portals-not" starts with "portal" too: a portal node by the rule (docs/scene-format.md).
            self.assertEqual(ES.gltf_material_count(path), 1)
        self.assertTrue(ES.is_portal_node("portal"))
        self.assertFalse(ES.is_portal_node("window-portal"))
        self.assertFalse(ES.is_portal_node(None))


class RegionMetrics(unittest.TestCase):
    def test_trimmed_count(self):
        self.assertEqual([M.trimmed_count(n) for n in (0, 1, 2, 1000, 1001, 5000)], [0, 0, 1, 1, 2, 5])

    def test_one_caustic_pixel_does_not_decide_the_robust_figures(self):
        e = np.full(500, 0.01)
        e[7] = 1e4
        m = M.region_metrics(e)
        self.assertAlmostEqual(m["relmse"], (499 * 0.01 + 1e4) / 500)
        self.assertAlmostEqual(m["relmse_trimmed"], 0.01)
        self.assertAlmostEqual(m["median"], 0.01)
        self.assertEqual((m["worst"], m["over_10x"], m["pixels"]), (1e4, 1, 500))
        self.assertIsNone(M.region_metrics(np.array([])))

    def test_masks_and_metrics(self):
        ids = np.array([[-1, 0, 1], [2, 2, 1]])
        masks = M.region_masks(ids, [("a", [0]), ("b", [1, 2]), ("empty", [7])])
        self.assertEqual(sorted(masks), ["a", "all", "b"])
        self.assertEqual(int(masks["b"].sum()), 4)
        ref = np.ones((2, 3, 3))
        image = ref.copy()
        image[0, 1] = 2.0  # object a: e = 1 / 1.01
        r = M.regions_metrics(image, ref, masks)
        self.assertAlmostEqual(r["a"]["relmse"], 1 / 1.01)
        self.assertAlmostEqual(r["b"]["relmse"], 0.0)
        self.assertAlmostEqual(r["all"]["relmse"], 1 / 1.01 / 6)

    def test_summary_efficiency_and_tables(self):
        def seed(relmse, seconds):
            reg = {"relmse": relmse, "relmse_trimmed": relmse / 2, "median": relmse / 4, "worst": 10 * relmse,
                   "over_10x": 0, "pixels": 6}
            return {"seconds": seconds, "regions": {"all": dict(reg), "a": dict(reg)}}
        cyc = M.summarise_regions([{"spp": 4, "seeds": [seed(0.4, 0.4)]}, {"spp": 16, "seeds": [seed(0.1, 1.6)]}])
        env = M.summarise_regions([{"spp": 4, "seeds": [seed(0.2, 0.2), seed(0.6, 0.1)]},
                                   {"spp": 16, "seeds": [seed(0.05, 0.8), seed(0.05, 0.9)]}])
        self.assertAlmostEqual(cyc["seconds_per_spp"], 0.1)
        self.assertAlmostEqual(env["seconds_per_spp"], 0.05)  # the fastest seed at the largest spp
        self.assertAlmostEqual(env["spp"][0]["regions"]["a"]["relmse"], 0.4)  # median of 0.2 and 0.6
        self.assertAlmostEqual(env["spp"][1]["regions"]["all"]["efficiency"], 1 / (0.05 * 16 * 0.05))
        scene = {"renderers": {M.CYCLES: cyc, "envpis product": env}, "pixels": {"a": 6, "all": 6},
                 "agreement": {"a": {"mean_relative_difference": 0.1, "ratio_of_means": 1.0}}}
        table = M.scene_table(scene, [4, 16])
        self.assertIn("| product | 0.4 / 0.05 |", table)
        self.assertIn("| 2.00 / 4.00 | 2.00 / 4.00 |", table)  # equal error in half the time, then half in half
        rows = M.object_table(scene, 16).splitlines()
        self.assertEqual(len(rows), 4)  # head, rule, a, all
        self.assertTrue(rows[2].startswith("| a | 6 | 0.1 (0.05) | 0.05 (0.025) | 4.00 | 0.100 | - | 1.000 |"), rows[2])


if __name__ == "__main__":
    unittest.main()
