#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Cycles side by side with envpis on matched sphere scenes (issue 11, item 5; issue 21, item 4; docs/cycles.md).

Run it through scripts/cycles-compare.sh, which finds or installs Blender and the tools. For each map and
roughness it renders the same scene in both renderers, a high-spp reference per renderer, and measures
every render against its own renderer's reference:

  relMSE = mean over pixels of (mean over R, G, B of (I - R)^2 / (R^2 + 0.01))   (apps/envpis/metrics.h)

over the sphere's pixels (pixel centre on the sphere) and over all pixels, the median over the seeds; also
by quartile of reference brightness, the log-log slope from 16 to 256 spp and the tail (worst pixel,
pixels 10x off). The metrics and the markdown tables are in scripts/cycles_metrics.py.
Sampling seconds: envpis's "wall seconds" of the sampling loop (tables apart); Cycles' render_time that
Blender writes into the EXR header (synchronisation, which includes building the world's importance
map, apart). Efficiency = 1 / (relMSE x seconds). The converged references of the two renderers are
compared with each other as a check that the scenes match (orientation, material, camera).

EXR files are read in one place, read_exr(), with oiiotool (Debian openimageio-tools): the header with
--info -v, the pixel values with --dumpdata. No Blender or Cycles code is used here; Blender only runs
scripts/cycles_scene.py.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import time

try:
    import numpy as np
except ImportError:
    sys.exit("cycles_compare.py: error: numpy is missing (Debian: apt-get install python3-numpy)")

import cycles_metrics as M  # noqa: E402  (the metrics and tables, pure functions; beside this file)

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
STUDIOLIGHTS = "/usr/share/blender/datafiles/studiolights/world"
REF_SEED = 1000003           # the references' seed: none of the measured seeds 0 .. --seeds - 1
ORTHO_HEIGHT = M.ORTHO_HEIGHT
STRATEGIES = ("bsdf", "env", "mis", "mis-comp", "product", "oracle",
              # through the scene's portals (render/strategy.h); envpis refuses them on a scene without
              "env-portal", "mis-portal", "mis-comp-portal", "product-portal")


class Failure(Exception):
    pass


def log(message):
    print("cycles-compare: " + message, flush=True)


def parse_list(text, convert, what):
    try:
        values = [convert(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise Failure("%s: expected a comma-separated list, got '%s'" % (what, text))
    if not values:
        raise Failure("%s: empty list" % what)
    return values


class Parser(argparse.ArgumentParser):
    def error(self, message):  # one line and exit status 1, as every envpis command (not argparse's usage + 2)
        raise Failure(message)


def parse_args(argv):
    p = Parser(prog="cycles-compare.sh",
                                description="Cycles vs envpis on matched sphere scenes (docs/cycles.md)",
               epilog="cycles-compare.sh also takes --install (or CYCLES_INSTALL=1): apt-get install blender "
                      "when it is missing.")
    p.add_argument("--maps", default="sunrise,studio,courtyard",
                   help="comma-separated maps: a name in %s, or a path to a 2:1 lat-long EXR (default "
                        "sunrise,studio,courtyard: two with a sun or small bright lights, one without)" % STUDIOLIGHTS)
    p.add_argument("--roughness", default="0.2,0.5",
                   help="Cycles roughness values; envpis's GGX alpha is their square (default 0.2,0.5)")
    p.add_argument("--size", type=int, default=256, help="image side in pixels (default 256)")
    p.add_argument("--spp", default="1,4,16,64,256", help="measured samples per pixel, ascending")
    p.add_argument("--seeds", type=int, default=3, help="renders per spp, seeds 0 .. K-1 (default 3)")
    p.add_argument("--ref-spp", type=int, default=4096, help="samples per pixel of each reference (default 4096; 0: 16 x the largest --spp)")
    p.add_argument("--strategies", default="bsdf,mis,mis-comp,product",
                   help="envpis strategies (default bsdf,mis,mis-comp,product)")
    p.add_argument("--sampler", default="sobol", help="envpis --sampler: sobol (default), padded (per-pair sequences, as Cycles) or independent")
    p.add_argument("--ref-strategy", default="mis", help="envpis reference strategy (default mis)")
    p.add_argument("--pattern", default="PROGRESSIVE_MULTI_JITTER", choices=("PROGRESSIVE_MULTI_JITTER", "SOBOL"),
                   help="Cycles sampling pattern (default Cycles' own default, PROGRESSIVE_MULTI_JITTER)")
    p.add_argument("--threads", type=int, default=2, help="threads of every render (default 2)")
    p.add_argument("--out", default=os.path.join(REPO, "out", "cycles-compare"), help="output directory")
    p.add_argument("--envpis", default=os.path.join(REPO, "build", "apps", "envpis", "envpis"),
                   help="the envpis binary")
    p.add_argument("--blender", default="blender", help="the Blender binary")
    p.add_argument("--reuse", action="store_true",
                   help="keep renders already in --out (same settings assumed) instead of rendering again")
    a = p.parse_args(argv)

    a.maps = [resolve_map(m) for m in parse_list(a.maps, str, "--maps")]
    a.roughness = parse_list(a.roughness, float, "--roughness")
    for r in a.roughness:
        if not 0 < r <= 1:
            raise Failure("--roughness: each value must be in (0, 1], got %g" % r)
    for name, lo, hi in (("seeds", 1, 64), ("size", 8, 4096)):
        check_range(a, name, lo, hi)
    check_envpis_args(a)
    return a


def check_range(a, name, lo, hi):
    if not lo <= getattr(a, name) <= hi:
        raise Failure("--%s: must be in %d..%d, got %d" % (name.replace("_", "-"), lo, hi, getattr(a, name)))


def check_envpis_args(a):
    """The options both side-by-sides share: --spp (a list), --ref-spp (0: 16 x the largest spp),
    --threads, --strategies, --ref-strategy, --sampler and the envpis binary."""
    a.spp = parse_list(a.spp, int, "--spp")
    if any(s < 1 for s in a.spp) or a.spp != sorted(set(a.spp)):
        raise Failure("--spp: positive integers in ascending order, got %s" % ",".join(map(str, a.spp)))
    a.ref_spp = a.ref_spp or 16 * a.spp[-1]
    if a.ref_spp < a.spp[-1]:
        raise Failure("--ref-spp (%d) must be at least the largest --spp (%d)" % (a.ref_spp, a.spp[-1]))
    check_range(a, "threads", 1, 1024)
    a.strategies = parse_list(a.strategies, str, "--strategies")
    for s in a.strategies + [a.ref_strategy]:
        if s not in STRATEGIES:
            raise Failure("unknown envpis strategy '%s' (%s)" % (s, ", ".join(STRATEGIES)))
    if a.sampler not in ("sobol", "padded", "independent"):
        raise Failure("--sampler: sobol, padded or independent, got '%s'" % a.sampler)
    if not (os.path.isfile(a.envpis) and os.access(a.envpis, os.X_OK)):
        raise Failure("no envpis binary at '%s' (build it: cmake --build build --target envpis_cmd, or --envpis)"
                      % a.envpis)


def resolve_map(name):
    # A bare name ("sunrise") is one of Blender's studio lights; anything with a directory or an extension
    # is a path.
    path = name if os.sep in name or os.path.splitext(name)[1] else os.path.join(STUDIOLIGHTS, name + ".exr")
    if not os.path.isfile(path):
        raise Failure("map '%s': no such file '%s'" % (name, path))
    return os.path.abspath(path)


def run(cmd, what):
    """Runs cmd; on failure raises with the tool's last line of stderr (its own one-line error)."""
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if proc.returncode != 0:
        lines = [l for l in (proc.stderr + proc.stdout).splitlines() if l.strip()]
        errors = [l for l in lines if "error" in l.lower()]
        raise Failure("%s failed (exit %d): %s" % (what, proc.returncode, (errors or lines or ["no output"])[-1]))
    return proc.stdout


# ---- EXR files: the one place that reads them ----

def read_exr(path, wanted=("R", "G", "B")):
    """(pixels as float64 [height, width, len(wanted)] in the order of wanted, header attributes as a dict
    of strings); wanted=("id",) reads envpis's object-id AOV."""
    # One oiiotool run prints the header ("    name: value" lines) and then every pixel
    # ("    Pixel (x, y): c0 c1 ...", scanline order from the top row, values with 9 decimals).
    out = run(["oiiotool", "--info", "-v", "--dumpdata", path], "oiiotool --info --dumpdata " + path)
    header, values = {}, []
    for line in out.splitlines():
        if line.startswith("    Pixel ("):
            values.append(line.split(":", 1)[1])
            continue
        m = re.match(r"\s+([^:]+):\s*(.*)$", line)
        if m:
            header[m.group(1).strip()] = m.group(2).strip().strip('"')
    channels = [c.strip() for c in header.get("channel list", "").split(",")]
    m = re.search(r":\s+(\d+) x\s+(\d+),", out)
    if not m or not all(c in channels for c in wanted):
        raise Failure("'%s': no %s channels (oiiotool says: %s)" % (path, ",".join(wanted), out.splitlines()[:2]))
    width, height = int(m.group(1)), int(m.group(2))
    data = np.array(" ".join(values).split(), dtype=np.float64)
    if data.size != width * height * len(channels):
        raise Failure("'%s': expected %d values, read %d" % (path, width * height * len(channels), data.size))
    data = data.reshape(height, width, len(channels))
    return data[:, :, [channels.index(c) for c in wanted]], header


def blender_seconds(header, path):
    """Cycles' sampling seconds: the view layer's render_time ("[HH:]MM:SS.cc"), written by Blender."""
    keys = [k for k in header if k.startswith("cycles.") and k.endswith(".render_time")]
    if not keys:
        raise Failure("'%s': no cycles.<view layer>.render_time in the EXR header" % path)
    seconds = 0.0
    for part in header[keys[0]].split(":"):
        seconds = seconds * 60 + float(part)
    return seconds


# ---- renders ----

def scene_json(path, size, alpha):
    # Fresnel 1 exactly: Schlick's F = f0 + (1 - f0)(1 - cos)^5 is 1 for f0 = 1 (render/materials/conductor.cpp).
    scene = {
        "camera": {"type": "orthographic", "from": [0, -10, 0], "to": [0, 0, 0], "up": [0, 0, 1],
                   "ortho_height": ORTHO_HEIGHT, "width": size, "height": size},
        "materials": {"ggx": {"type": "conductor", "roughness": alpha, "reflectance": 1.0}},
        "objects": [{"type": "sphere", "name": "sphere", "center": [0, 0, 0], "radius": 1, "material": "ggx"}],
    }
    with open(path, "w") as f:
        json.dump(scene, f, indent=1)


def envpis_render(a, scene, env, strategy, spp, seed, out):
    """Renders (or with --reuse keeps) one envpis image; returns its sampling seconds."""
    side = out[:-4] + ".json"
    if a.reuse and os.path.isfile(out) and os.path.isfile(side):
        with open(side) as f:
            return json.load(f)["seconds"]
    cmd = [a.envpis, "render", "--scene", scene, "--env", env, "--env-filter", "nearest",
           "--integrator", "direct", "--strategy", strategy, "--sampler", a.sampler, "--spp", str(spp),
           "--seed", str(seed), "--threads", str(a.threads), "--quiet", "--out", out]
    stdout = run(cmd, "envpis render " + strategy)
    m = re.search(r"^wall seconds\s+([0-9.eE+-]+)", stdout, re.M)
    if not m:
        raise Failure("envpis render printed no 'wall seconds' line")
    with open(side, "w") as f:
        json.dump({"command": cmd, "seconds": float(m.group(1))}, f)
    return float(m.group(1))


def cycles_renders(a, env, roughness, jobs):
    """Renders every (spp, seed, file) in jobs in one Blender process (files kept with --reuse)."""
    todo = [j for j in jobs if not (a.reuse and os.path.isfile(j[2]))]
    if not todo:
        return
    cmd = [a.blender, "-b", "--factory-startup", "--python-exit-code", "1",
           "--python", os.path.join(HERE, "cycles_scene.py"), "--",
           "--map", env, "--roughness", repr(roughness), "--size", str(a.size), "--ortho-height", repr(ORTHO_HEIGHT),
           "--threads", str(a.threads), "--pattern", a.pattern]
    for spp, seed, path in todo:
        cmd += ["--render", "%d:%d:%s" % (spp, seed, path)]
    run(cmd, "blender (Cycles)")


def loadavg():
    """The 1-minute load average (the machine is shared: timings are only as good as it was quiet)."""
    try:
        with open("/proc/loadavg") as f:
            return float(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        return None


def measure_scene(a, env, roughness):
    alpha = roughness * roughness
    map_name = os.path.splitext(os.path.basename(env))[0]
    name = "%s-r%g" % (map_name, roughness)
    d = os.path.join(a.out, name)
    os.makedirs(d, exist_ok=True)
    mask = M.sphere_mask(a.size)
    seeds = list(range(a.seeds))
    result = {"name": name, "map": env, "map_name": map_name, "cycles_roughness": roughness, "alpha": alpha,
              "renderers": {}}
    start = time.time()
    result["loadavg_before"] = loadavg()

    # Cycles: the reference and every measured render in one Blender run.
    t0 = time.time()
    cref = os.path.join(d, "cycles-ref-%d.exr" % a.ref_spp)
    jobs = [(a.ref_spp, REF_SEED, cref)]
    jobs += [(s, k, os.path.join(d, "cycles-%d-%d.exr" % (s, k))) for s in a.spp for k in seeds]
    log("%s: Cycles, %d renders" % (name, len(jobs)))
    cycles_renders(a, env, roughness, jobs)
    renders = {M.CYCLES: {(s, k): p for s, k, p in jobs[1:]}}
    refs = {M.CYCLES: cref}
    log("%s: Cycles done in %.0f s" % (name, time.time() - t0))

    # envpis: each strategy at each spp and seed, and its own reference.
    scene = os.path.join(d, "scene.json")
    scene_json(scene, a.size, alpha)
    eref = os.path.join(d, "envpis-ref-%s-%d.exr" % (a.ref_strategy, a.ref_spp))
    t0 = time.time()
    log("%s: envpis reference (%s, %d spp)" % (name, a.ref_strategy, a.ref_spp))
    envpis_render(a, scene, env, a.ref_strategy, a.ref_spp, REF_SEED, eref)
    seconds = {}
    for strategy in a.strategies:
        key = "envpis " + strategy
        renders[key], refs[key] = {}, eref
        for s in a.spp:
            for k in seeds:
                out = os.path.join(d, "envpis-%s-%d-%d.exr" % (strategy, s, k))
                seconds[(key, s, k)] = envpis_render(a, scene, env, strategy, s, k, out)
                renders[key][(s, k)] = out
    log("%s: envpis done in %.0f s" % (name, time.time() - t0))
    result["render_seconds"] = time.time() - start

    # Measure every render against its own renderer's reference. The brightness quartiles are one
    # partition of the sphere's pixels for both renderers: by the mean over channels of the mean of the
    # two references (they agree to under 1%, see "agreement").
    ref_images = {cref: read_exr(cref)[0], eref: read_exr(eref)[0]}
    c_ref, e_ref = ref_images[cref], ref_images[eref]
    quartile = M.brightness_quartiles(((c_ref + e_ref) / 2).mean(axis=2)[mask])
    for key in renders:
        ref = ref_images[refs[key]]
        rows = []
        for s in a.spp:
            per_seed = []
            for k in seeds:
                image, header = read_exr(renders[key][(s, k)])
                sec = blender_seconds(header, renders[key][(s, k)]) if key == M.CYCLES else seconds[(key, s, k)]
                m = M.image_metrics(image, ref, mask, quartile)
                m.update(seed=k, seconds=sec)
                per_seed.append(m)
            rows.append({"spp": s, "seeds": per_seed})
        result["renderers"][key] = dict(reference=refs[key], **M.summarise(rows))
    result["agreement"] = M.agreement(c_ref, e_ref, mask)
    result["sphere_pixels"] = int(mask.sum())
    result["seconds"] = time.time() - start
    result["loadavg_after"] = loadavg()
    log("%s: measured; %.0f s in all" % (name, result["seconds"]))
    return result


def main(argv):
    try:
        a = parse_args(argv)
        os.makedirs(a.out, exist_ok=True)
        start = time.time()
        load_before = loadavg()
        results = [measure_scene(a, env, r) for env in a.maps for r in a.roughness]
        load_after = loadavg()
        loads = [x for x in [load_before, load_after] + [r[k] for r in results
                                                          for k in ("loadavg_before", "loadavg_after")] if x is not None]
        note = "%d cores; 1-minute load average %s to %s during the run%s." % (
            os.cpu_count() or 0, M.fmt(min(loads) if loads else None, ".1f"),
            M.fmt(max(loads) if loads else None, ".1f"),
            " (timings, hence efficiency, are indicative only when it exceeds the cores; relMSE is not affected)"
            if loads and max(loads) > (os.cpu_count() or 1) else "")
        summary = {"command": ["scripts/cycles-compare.sh"] + argv, "size": a.size, "spp": a.spp, "seeds": a.seeds,
                   "ref_spp": a.ref_spp, "threads": a.threads, "envpis_sampler": a.sampler,
                   "cycles_pattern": a.pattern, "ortho_height": ORTHO_HEIGHT, "loadavg": [load_before, load_after],
                   "relmse_definition": "mean over the sphere's pixels of mean over RGB of (I-R)^2/(R^2+0.01), R = "
                                        "the renderer's own reference; median over seeds",
                   "quartile_definition": "quarters of the sphere's pixels ranked by the channel mean of the mean "
                                          "of the two references; quartiles[3] is the brightest",
                   "tail_definition": "worst: the largest per-pixel error on the sphere; over_10x: pixels with "
                                      "error > 100; medians over seeds",
                   "slope_definition": "least-squares slope of log relMSE on log spp over the spp in [16, 256]",
                   "efficiency_definition": "1/(relMSE x spp x seconds_per_spp), seconds_per_spp from the fastest seed "
                                            "at the largest spp",
                   "scenes": results, "wall_seconds": time.time() - start}
        with open(os.path.join(a.out, "results.json"), "w") as f:
            json.dump(summary, f, indent=1)
        settings = {k: getattr(a, k) for k in ("size", "threads", "sampler", "pattern", "ref_strategy", "ref_spp",
                                               "seeds", "spp")}
        md = M.markdown(settings, results, note)
        with open(os.path.join(a.out, "results.md"), "w") as f:
            f.write(md)
        print(md)
        log("done in %.0f s; %s/results.md and results.json" % (time.time() - start, a.out))
        return 0
    except Failure as e:
        print("cycles-compare: error: %s" % e, file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
