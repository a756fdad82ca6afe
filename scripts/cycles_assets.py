#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Cycles side by side with envpis on the glTF asset scenes (issue 22, item 3; docs/cycles.md, "The asset
scenes"). Run it through scripts/cycles-assets.sh, which finds or installs Blender and the tools.

For each scene and map: Cycles renders a reference and every (spp, seed) in one Blender run
(scripts/cycles_assets_scene.py builds the scene from the envpis scene file); envpis renders its own
reference (--ref-strategy, with the object-id AOV) and every strategy at every (spp, seed) with
`render --integrator path --max-depth D --env-filter nearest`. Each render is measured against its own
renderer's reference, per object (envpis's object-id AOV, one mask per scene-file object, used for both
renderers: same camera, same geometry) and over the whole image: relMSE (apps/envpis/metrics.h), the
robust relMSE without each region's top 0.1% of pixels, the median per-pixel error, the tail (worst
pixel, pixels 10x off); medians over the seeds. Seconds: envpis's "wall seconds" (sampling only),
Cycles' render_time from the EXR header; efficiency = 1 / (relMSE x seconds), relative to Cycles'. The two
references are compared with each other (mean relative difference per object): what the renderers'
converged images do not share. The metrics are scripts/cycles_metrics.py's; EXRs are read by
scripts/cycles_compare.py's read_exr.
"""
import json
import os
import re
import sys
import time

import cycles_compare as C  # noqa: E402  (EXR reading, commands, maps, one-line errors; beside this file)
import cycles_metrics as M  # noqa: E402
import envpis_scene as ES  # noqa: E402

HERE, REPO = C.HERE, C.REPO
Failure = C.Failure
REF_SEED = C.REF_SEED
STRATEGIES = C.STRATEGIES


def log(message):
    print("cycles-assets: " + message, flush=True)


def parse_args(argv):
    p = C.Parser(prog="cycles-assets.sh", description="Cycles vs envpis on the glTF asset scenes (docs/cycles.md)",
                 epilog="cycles-assets.sh also takes --install (or CYCLES_INSTALL=1): apt-get install blender "
                        "when it is missing.")
    p.add_argument("--scenes", default="bunny,clearcoat,engine,suzanne-closeup",
                   help="comma-separated scenes: NAME for scenes/assets-NAME.json, or a path (default all four)")
    p.add_argument("--maps", default="sunrise,studio", help="maps: names in %s, or paths" % C.STUDIOLIGHTS)
    p.add_argument("--width", type=int, default=128, help="image width (default 128)")
    p.add_argument("--height", type=int, default=72, help="image height (default 72)")
    p.add_argument("--spp", default="16,64", help="measured samples per pixel, ascending (default 16,64)")
    p.add_argument("--seeds", type=int, default=3, help="renders per spp, seeds 0 .. K-1 (default 3)")
    p.add_argument("--ref-spp", type=int, default=0, help="reference spp (default 16 x the largest --spp)")
    p.add_argument("--max-depth", type=int, default=8,
                   help="envpis --max-depth (surface vertices); Cycles max bounces = this - 1 (default 8)")
    p.add_argument("--strategies", default="mis,mis-comp,product", help="envpis strategies")
    p.add_argument("--ref-strategy", default="mis", help="envpis reference strategy (default mis)")
    p.add_argument("--sampler", default="sobol", help="envpis --sampler: sobol (default), padded (per-pair sequences, as Cycles) or independent")
    p.add_argument("--pattern", default="PROGRESSIVE_MULTI_JITTER", choices=("PROGRESSIVE_MULTI_JITTER", "SOBOL"),
                   help="Cycles sampling pattern (default PROGRESSIVE_MULTI_JITTER)")
    p.add_argument("--threads", type=int, default=2, help="threads of every render (default 2)")
    p.add_argument("--out", default=os.path.join(REPO, "out", "cycles-assets"), help="output directory")
    p.add_argument("--envpis", default=os.path.join(REPO, "build", "apps", "envpis", "envpis"), help="envpis binary")
    p.add_argument("--blender", default="blender", help="the Blender binary")
    p.add_argument("--reuse", action="store_true", help="keep renders already in --out (same settings assumed)")
    a = p.parse_args(argv)
    a.scenes = [resolve_scene(s) for s in C.parse_list(a.scenes, str, "--scenes")]
    a.maps = [C.resolve_map(m) for m in C.parse_list(a.maps, str, "--maps")]
    for name, lo, hi in (("seeds", 1, 64), ("width", 8, 4096), ("height", 8, 4096), ("max_depth", 1, 64)):
        C.check_range(a, name, lo, hi)
    C.check_envpis_args(a)
    return a


def resolve_scene(name):
    """A bare name is scenes/assets-NAME.json; the scene's files must exist (the assets are fetched by
    scripts/fetch-assets.sh, the models are Debian's assimp-testmodels)."""
    path = name if os.sep in name or name.endswith(".json") else os.path.join(REPO, "scenes", "assets-%s.json" % name)
    if not os.path.isfile(path):
        raise Failure("scene '%s': no such file '%s'" % (name, path))
    try:
        scene = ES.load_scene(path)
    except ES.SceneError as e:
        raise Failure(str(e))
    for o in scene["objects"]:
        if "file" in o and not os.path.isfile(o["file"]):
            raise Failure("scene '%s': missing '%s' (run scripts/fetch-assets.sh; the glTF2 models are Debian's "
                          "assimp-testmodels)" % (name, o["file"]))
    return os.path.abspath(path)


def envpis_render(a, scene, env, strategy, spp, seed, out, id_out=None):
    """One envpis render (kept with --reuse); returns (sampling seconds, the scene's object count)."""
    side = out[:-4] + ".json"
    if a.reuse and os.path.isfile(out) and os.path.isfile(side) and (id_out is None or os.path.isfile(id_out)):
        with open(side) as f:
            s = json.load(f)
        return s["seconds"], s["objects"]
    cmd = [a.envpis, "render", "--scene", scene, "--env", env, "--env-filter", "nearest", "--integrator", "path",
           "--max-depth", str(a.max_depth), "--strategy", strategy, "--sampler", a.sampler, "--spp", str(spp),
           "--seed", str(seed), "--width", str(a.width), "--height", str(a.height), "--threads", str(a.threads),
           "--quiet", "--out", out] + (["--id-out", id_out] if id_out else [])
    stdout = C.run(cmd, "envpis render " + strategy)
    m = re.search(r"^wall seconds\s+([0-9.eE+-]+)", stdout, re.M)
    n = re.search(r"^scene\s.*\((\d+) objects\)", stdout, re.M)
    if not m or not n:
        raise Failure("envpis render printed no 'wall seconds' or 'scene ... (N objects)' line")
    with open(side, "w") as f:
        json.dump({"command": cmd, "seconds": float(m.group(1)), "objects": int(n.group(1))}, f)
    return float(m.group(1)), int(n.group(1))


def cycles_renders(a, scene, env, jobs):
    todo = [j for j in jobs if not (a.reuse and os.path.isfile(j[2]))]
    if not todo:
        return
    cmd = [a.blender, "-b", "--factory-startup", "--python-exit-code", "1",
           "--python", os.path.join(HERE, "cycles_assets_scene.py"), "--", "--scene", scene, "--map", env,
           "--width", str(a.width), "--height", str(a.height), "--max-depth", str(a.max_depth),
           "--threads", str(a.threads), "--pattern", a.pattern]
    for spp, seed, path in todo:
        cmd += ["--render", "%d:%d:%s" % (spp, seed, path)]
    C.run(cmd, "blender (Cycles)")


def masks(a, scene_path, id_file, objects):
    """The object masks from envpis's object-id AOV, one per scene-file object; the whole image only
    (and a note) when the ids cannot be assigned to the scene file's objects."""
    ids = C.read_exr(id_file, ("id",))[0][:, :, 0].astype(int)
    groups = ES.object_id_groups(ES.load_scene(scene_path))
    count = sum(len(g[1]) for g in groups)
    if count != objects:
        return M.region_masks(ids, []), "envpis made %d objects, the scene file's glTF give %d: whole image only" % (
            objects, count)
    return M.region_masks(ids, groups), None


class Renders:
    """Every image of one scene and map: {renderer: {(spp, seed): path}}, each renderer's reference, the
    envpis sampling seconds, envpis's object-id AOV and object count."""

    def __init__(self, d, a):
        self.cref = os.path.join(d, "cycles-ref-%d.exr" % a.ref_spp)
        self.eref = os.path.join(d, "envpis-ref-%s-%d.exr" % (a.ref_strategy, a.ref_spp))
        self.id_file = os.path.join(d, "object-id.exr")
        self.paths = {M.CYCLES: {(s, k): os.path.join(d, "cycles-%d-%d.exr" % (s, k))
                                 for s in a.spp for k in range(a.seeds)}}
        self.refs = {M.CYCLES: self.cref}
        self.seconds, self.objects = {}, 0


def render_all(a, scene_path, env, d, name):
    """Cycles (one Blender run: reference and every spp x seed), then envpis's reference (with the
    object ids) and every strategy x spp x seed."""
    r = Renders(d, a)
    start = time.time()
    jobs = [(a.ref_spp, REF_SEED, r.cref)] + [(s, k, p) for (s, k), p in r.paths[M.CYCLES].items()]
    log("%s: Cycles, %d renders" % (name, len(jobs)))
    cycles_renders(a, scene_path, env, jobs)
    log("%s: Cycles done in %.0f s; envpis reference (%s, %d spp)" % (name, time.time() - start, a.ref_strategy,
                                                                      a.ref_spp))
    r.objects = envpis_render(a, scene_path, env, a.ref_strategy, a.ref_spp, REF_SEED, r.eref, r.id_file)[1]
    for strategy in a.strategies:
        key = "envpis " + strategy
        r.paths[key], r.refs[key] = {}, r.eref
        for s in a.spp:
            for k in range(a.seeds):
                out = os.path.join(d, "envpis-%s-%d-%d.exr" % (strategy, s, k))
                r.seconds[(key, s, k)] = envpis_render(a, scene_path, env, strategy, s, k, out)[0]
                r.paths[key][(s, k)] = out
    return r


def measure_all(a, r, regions, result):
    """Every render against its own renderer's reference, per region; the references' agreement and its
    noise floor."""
    ref_images = {r.cref: C.read_exr(r.cref)[0], r.eref: C.read_exr(r.eref)[0]}
    pooled = []  # envpis's renders at the largest spp: the same converged image as its reference
    for key, paths in r.paths.items():
        rows = []
        for s in a.spp:
            per_seed = []
            for k in range(a.seeds):
                image, header = C.read_exr(paths[(s, k)])
                if key != M.CYCLES and s == a.spp[-1]:
                    pooled.append(image)
                sec = C.blender_seconds(header, paths[(s, k)]) if key == M.CYCLES else r.seconds[(key, s, k)]
                per_seed.append({"seed": k, "seconds": sec,
                                 "regions": M.regions_metrics(image, ref_images[r.refs[key]], regions)})
            rows.append({"spp": s, "seeds": per_seed})
        result["renderers"][key] = dict(reference=r.refs[key], **M.summarise_regions(rows))
    result["agreement"] = M.region_agreement(ref_images[r.cref], ref_images[r.eref], regions)
    # How far apart two images of the same renderer are at about the references' noise: envpis's
    # reference against the mean of its renders at the largest spp (len(pooled) x that spp samples).
    # A Cycles-envpis difference at this level is the references' noise, not a mismatch.
    result["noise_floor"] = M.region_agreement(sum(pooled) / len(pooled), ref_images[r.eref], regions)
    result["noise_floor_spp"] = len(pooled) * a.spp[-1]


def measure(a, scene_path, env):
    scene_name = os.path.splitext(os.path.basename(scene_path))[0].replace("assets-", "")
    map_name = os.path.splitext(os.path.basename(env))[0]
    name = "%s-%s" % (scene_name, map_name)
    d = os.path.join(a.out, name)
    os.makedirs(d, exist_ok=True)
    result = {"name": name, "scene": scene_path, "scene_name": scene_name, "map": env, "map_name": map_name,
              "renderers": {}, "loadavg_before": C.loadavg()}
    start = time.time()
    r = render_all(a, scene_path, env, d, name)
    result["render_seconds"] = time.time() - start
    regions, result["note"] = masks(a, scene_path, r.id_file, r.objects)
    measure_all(a, r, regions, result)
    result["pixels"] = {n: int(m.sum()) for n, m in regions.items()}
    result["seconds"] = time.time() - start
    result["loadavg_after"] = C.loadavg()
    log("%s: measured; %.0f s in all" % (name, result["seconds"]))
    return result


def markdown(a, results, note):
    lines = ["# Cycles vs envpis, glTF asset scenes", "",
             "%dx%d, path tracing to %d surface vertices (Cycles max bounces %d), %d threads; envpis `--sampler %s "
             "--env-filter nearest`, Cycles %s; references: Cycles and envpis %s at %d spp, each renderer against "
             "its own; medians over %d seed(s). relMSE as apps/envpis/metrics.h; robust: without each region's "
             "top 0.1%% of pixels; median e: the median per-pixel error; efficiency = 1 / (relMSE x spp x ms "
             "per spp) relative to Cycles'. %s"
             % (a.width, a.height, a.max_depth, a.max_depth - 1, a.threads, a.sampler, a.pattern, a.ref_strategy,
                a.ref_spp, a.seeds, note), ""]
    for r in results:
        lines += ["## %s under %s" % (r["scene_name"], r["map_name"]), "", M.scene_table(r, a.spp),
                  "Per object at %d spp (masks: envpis's object ids; noise floor: envpis's reference against "
                  "the mean of its %d-spp renders, %d spp pooled):" % (a.spp[-1], a.spp[-1], r["noise_floor_spp"]), "",
                  M.object_table(r, a.spp[-1])]
        if r["note"]:
            lines += ["Note: " + r["note"], ""]
    return "\n".join(lines) + "\n"


def main(argv):
    try:
        a = parse_args(argv)
        os.makedirs(a.out, exist_ok=True)
        start, load_before = time.time(), C.loadavg()
        results = [measure(a, s, env) for s in a.scenes for env in a.maps]
        loads = [x for x in [load_before, C.loadavg()] + [r[k] for r in results for k in ("loadavg_before",
                                                                                         "loadavg_after")]
                 if x is not None]
        busy = loads and max(loads) > (os.cpu_count() or 1)
        note = "%d cores; 1-minute load average %s to %s during the run%s." % (
            os.cpu_count() or 0, M.fmt(min(loads) if loads else None, ".1f"),
            M.fmt(max(loads) if loads else None, ".1f"),
            " (above the cores: timings, hence efficiency, are indicative only)" if busy else "")
        summary = {"command": ["scripts/cycles-assets.sh"] + argv, "width": a.width, "height": a.height,
                   "spp": a.spp, "seeds": a.seeds, "ref_spp": a.ref_spp, "max_depth": a.max_depth,
                   "cycles_max_bounces": a.max_depth - 1, "threads": a.threads, "envpis_sampler": a.sampler,
                   "cycles_pattern": a.pattern, "loadavg": loads, "scenes": results,
                   "trim_definition": "relmse_trimmed: relMSE without each region's ceil(n/1000) largest pixel errors",
                   "wall_seconds": time.time() - start}
        with open(os.path.join(a.out, "results.json"), "w") as f:
            json.dump(summary, f, indent=1)
        md = markdown(a, results, note)
        with open(os.path.join(a.out, "results.md"), "w") as f:
            f.write(md)
        print(md)
        log("done in %.0f s; %s/results.md and results.json" % (time.time() - start, a.out))
        return 0
    except (Failure, ES.SceneError) as e:
        print("cycles-assets: error: %s" % e, file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
