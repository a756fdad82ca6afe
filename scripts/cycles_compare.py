#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Cycles side by side with envpis on matched sphere scenes (issue 11, item 5; docs/cycles.md).

Run it through scripts/cycles-compare.sh, which finds or installs Blender and the tools. For each map and
roughness it renders the same scene in both renderers, a high-spp reference per renderer, and measures
every render against its own renderer's reference:

  relMSE = mean over pixels of (mean over R, G, B of (I - R)^2 / (R^2 + 0.01))   (apps/envpis/metrics.h)

over the sphere's pixels (pixel centre on the sphere) and over all pixels, the median over the seeds.
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
import math
import os
import re
import subprocess
import sys
import time

try:
    import numpy as np
except ImportError:
    sys.exit("cycles_compare.py: error: numpy is missing (Debian: apt-get install python3-numpy)")

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
STUDIOLIGHTS = "/usr/share/blender/datafiles/studiolights/world"
REF_SEED = 1000003           # the references' seed: none of the measured seeds 0 .. --seeds - 1
ORTHO_HEIGHT = 2.2           # film height in world units: the unit sphere fills 1/1.1 of it
REL_EPSILON = 0.01           # apps/envpis/metrics.h kRelEpsilon
STRATEGIES = ("bsdf", "env", "mis", "mis-comp", "product", "oracle")


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
    p.add_argument("--maps", default="sunrise,studio",
                   help="comma-separated maps: a name in %s, or a path to a 2:1 lat-long EXR" % STUDIOLIGHTS)
    p.add_argument("--roughness", default="0.2,0.5",
                   help="Cycles roughness values; envpis's GGX alpha is their square (default 0.2,0.5)")
    p.add_argument("--size", type=int, default=256, help="image side in pixels (default 256)")
    p.add_argument("--spp", default="1,4,16,64,256", help="measured samples per pixel, ascending")
    p.add_argument("--seeds", type=int, default=3, help="renders per spp, seeds 0 .. K-1 (default 3)")
    p.add_argument("--ref-spp", type=int, default=4096, help="samples per pixel of each reference (default 4096)")
    p.add_argument("--strategies", default="mis,mis-comp,product", help="envpis strategies")
    p.add_argument("--sampler", default="sobol", help="envpis --sampler (default sobol)")
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
    a.spp = parse_list(a.spp, int, "--spp")
    if any(s < 1 for s in a.spp) or a.spp != sorted(set(a.spp)):
        raise Failure("--spp: positive integers in ascending order, got %s" % ",".join(map(str, a.spp)))
    if not 1 <= a.seeds <= 64:
        raise Failure("--seeds: must be in 1..64, got %d" % a.seeds)
    if not 8 <= a.size <= 4096:
        raise Failure("--size: must be in 8..4096, got %d" % a.size)
    if a.ref_spp < a.spp[-1]:
        raise Failure("--ref-spp (%d) must be at least the largest --spp (%d)" % (a.ref_spp, a.spp[-1]))
    if not 1 <= a.threads <= 1024:
        raise Failure("--threads: must be in 1..1024, got %d" % a.threads)
    a.strategies = parse_list(a.strategies, str, "--strategies")
    for s in a.strategies + [a.ref_strategy]:
        if s not in STRATEGIES:
            raise Failure("unknown envpis strategy '%s' (%s)" % (s, ", ".join(STRATEGIES)))
    if a.sampler not in ("sobol", "independent"):
        raise Failure("--sampler: sobol or independent, got '%s'" % a.sampler)
    if not (os.path.isfile(a.envpis) and os.access(a.envpis, os.X_OK)):
        raise Failure("no envpis binary at '%s' (build it: cmake --build build --target envpis_cmd, or --envpis)"
                      % a.envpis)
    return a


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

def read_exr(path):
    """(pixels as float64 [height, width, 3] in R, G, B order, header attributes as a dict of strings)."""
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
    if not m or not all(c in channels for c in "RGB"):
        raise Failure("'%s': not an RGB image (oiiotool says: %s)" % (path, out.splitlines()[:2]))
    width, height = int(m.group(1)), int(m.group(2))
    data = np.array(" ".join(values).split(), dtype=np.float64)
    if data.size != width * height * len(channels):
        raise Failure("'%s': expected %d values, read %d" % (path, width * height * len(channels), data.size))
    data = data.reshape(height, width, len(channels))
    rgb = data[:, :, [channels.index(c) for c in "RGB"]]
    return rgb, header


def blender_seconds(header, path):
    """Cycles' sampling seconds: the view layer's render_time ("[HH:]MM:SS.cc"), written by Blender."""
    keys = [k for k in header if k.startswith("cycles.") and k.endswith(".render_time")]
    if not keys:
        raise Failure("'%s': no cycles.<view layer>.render_time in the EXR header" % path)
    seconds = 0.0
    for part in header[keys[0]].split(":"):
        seconds = seconds * 60 + float(part)
    return seconds


# ---- metrics ----

def sphere_mask(size):
    """Pixels whose centre sees the unit sphere through the orthographic camera (envpis's object-id)."""
    c = (np.arange(size) + 0.5) / size * ORTHO_HEIGHT - ORTHO_HEIGHT / 2
    x, y = np.meshgrid(c, c)
    return x * x + y * y < 1.0


def rel_sq_error(image, ref):
    return np.mean((image - ref) ** 2 / (ref * ref + REL_EPSILON), axis=2)


def relmse(image, ref, mask):
    e = rel_sq_error(image, ref)
    return float(e[mask].mean()), float(e.mean())


def agreement(cycles_ref, envpis_ref, mask):
    """How far apart the two converged references are on the sphere."""
    c, e = cycles_ref[mask], envpis_ref[mask]
    return {
        "mean_relative_difference": float(np.mean(np.abs(c - e) / (np.abs(e) + REL_EPSILON))),
        "ratio_of_means": float(c.mean() / e.mean()),
        "relmse_cycles_vs_envpis": float(np.mean(np.mean((c - e) ** 2 / (e * e + REL_EPSILON), axis=1))),
        "p95_relative_difference": float(np.percentile(np.mean(np.abs(c - e), axis=1) /
                                                       (np.mean(np.abs(e), axis=1) + REL_EPSILON), 95)),
    }


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


def median(values):
    return float(np.median(values))


def measure_scene(a, env, roughness):
    alpha = roughness * roughness
    name = "%s-r%g" % (os.path.splitext(os.path.basename(env))[0], roughness)
    d = os.path.join(a.out, name)
    os.makedirs(d, exist_ok=True)
    mask = sphere_mask(a.size)
    seeds = list(range(a.seeds))
    result = {"name": name, "map": env, "cycles_roughness": roughness, "alpha": alpha, "renderers": {}}

    # Cycles: the reference and every measured render in one Blender run.
    t0 = time.time()
    cref = os.path.join(d, "cycles-ref-%d.exr" % a.ref_spp)
    jobs = [(a.ref_spp, REF_SEED, cref)]
    jobs += [(s, k, os.path.join(d, "cycles-%d-%d.exr" % (s, k))) for s in a.spp for k in seeds]
    log("%s: Cycles, %d renders" % (name, len(jobs)))
    cycles_renders(a, env, roughness, jobs)
    renders = {"cycles": {(s, k): p for s, k, p in jobs[1:]}}
    refs = {"cycles": cref}
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

    # Measure every render against its own renderer's reference.
    ref_images = {}
    for key in renders:
        if refs[key] not in ref_images:
            ref_images[refs[key]] = read_exr(refs[key])[0]
        ref = ref_images[refs[key]]
        rows = []
        for s in a.spp:
            per_seed = []
            for k in seeds:
                image, header = read_exr(renders[key][(s, k)])
                sec = blender_seconds(header, renders[key][(s, k)]) if key == "cycles" else seconds[(key, s, k)]
                sphere, whole = relmse(image, ref, mask)
                per_seed.append({"seed": k, "seconds": sec, "relmse_sphere": sphere, "relmse_all": whole})
            rows.append({"spp": s, "seeds": per_seed,
                         "relmse_sphere": median([r["relmse_sphere"] for r in per_seed]),
                         "relmse_all": median([r["relmse_all"] for r in per_seed]),
                         "seconds": median([r["seconds"] for r in per_seed])})
        # Seconds per spp from the largest spp (the most samples: the least timer and start-up noise, and
        # Blender's render_time has 10 ms steps), the fastest seed (other processes only ever slow a
        # render down; envpis compare also keeps the minimum of its timing repeats). Efficiency at any
        # spp uses spp x this rate.
        rate = min(r["seconds"] for r in rows[-1]["seeds"]) / rows[-1]["spp"]
        for r in rows:  # None when a time rounds to 0 (Blender's 10 ms steps on a tiny image) or relMSE is 0
            r["efficiency_sphere"] = 1.0 / (r["relmse_sphere"] * r["spp"] * rate) \
                if r["relmse_sphere"] > 0 and rate > 0 else None
            r["efficiency_all"] = 1.0 / (r["relmse_all"] * r["spp"] * rate) if r["relmse_all"] > 0 and rate > 0 else None
        slope = None
        if len(rows) >= 2 and rows[-1]["relmse_sphere"] > 0 and rows[-2]["relmse_sphere"] > 0:
            slope = math.log(rows[-1]["relmse_sphere"] / rows[-2]["relmse_sphere"]) / \
                math.log(rows[-1]["spp"] / rows[-2]["spp"])
        result["renderers"][key] = {"reference": refs[key], "seconds_per_spp": rate, "slope_sphere": slope,
                                    "spp": rows}
    c_ref, e_ref = ref_images[cref], ref_images[eref]
    result["agreement"] = agreement(c_ref, e_ref, mask)
    result["sphere_pixels"] = int(mask.sum())
    return result


# ---- report ----

def fmt(v, spec=".3g"):
    return "-" if v is None else format(v, spec)


def markdown(a, results, loaded_note):
    lines = ["# Cycles vs envpis, matched sphere scenes", ""]
    lines.append("%dx%d, orthographic, direct light, %d threads; envpis `--sampler %s --env-filter nearest`, "
                 "Cycles %s; references: Cycles and envpis %s at %d spp; relMSE medians over %d seed(s), "
                 "each renderer against its own reference. %s"
                 % (a.size, a.size, a.threads, a.sampler, a.pattern, a.ref_strategy, a.ref_spp, a.seeds, loaded_note))
    lines.append("")
    top = a.spp[-1]
    for res in results:
        ag = res["agreement"]
        lines.append("## %s, Cycles roughness %g (alpha %g)" % (os.path.basename(res["map"]), res["cycles_roughness"],
                                                                 res["alpha"]))
        lines.append("")
        lines.append("Converged references, Cycles vs envpis on the sphere: mean relative difference %.4f, "
                     "ratio of means %.4f, 95th percentile %.4f." % (ag["mean_relative_difference"],
                                                                   ag["ratio_of_means"], ag["p95_relative_difference"]))
        lines.append("")
        head = "| renderer | " + " | ".join("relMSE %d spp" % s for s in a.spp) + \
            " | slope %d-%d | ms/spp | relMSE all px %d spp | relMSE Cycles / this at %d spp " \
            "| efficiency vs Cycles, sphere (all px) at %d spp |" \
            % (a.spp[-2] if len(a.spp) > 1 else top, top, top, top, top)
        lines += [head, "|" + "---|" * (len(a.spp) + 6)]
        cyc = res["renderers"]["cycles"]["spp"][-1]
        for key, r in res["renderers"].items():
            last = r["spp"][-1]
            ratio = lambda k: (last[k] / cyc[k]) if last[k] and cyc[k] else None
            # The equal-spp relMSE ratio needs no timing, so a busy machine does not change it.
            spp_ratio = cyc["relmse_sphere"] / last["relmse_sphere"] if last["relmse_sphere"] else None
            lines.append("| %s | %s | %s | %.2f | %s | %s | %s (%s) |" % (
                key, " | ".join(fmt(x["relmse_sphere"]) for x in r["spp"]), fmt(r["slope_sphere"], ".2f"),
                1000 * r["seconds_per_spp"], fmt(last["relmse_all"]), fmt(spp_ratio, ".2f"),
                fmt(ratio("efficiency_sphere"), ".2f"), fmt(ratio("efficiency_all"), ".2f")))
        lines.append("")
        # The ratio at every spp: stratified samples make it depend on the spp.
        lines += ["| efficiency vs Cycles, sphere | " + " | ".join("%d spp" % s for s in a.spp) + " |",
                  "|" + "---|" * (len(a.spp) + 1)]
        cycles_rows = res["renderers"]["cycles"]["spp"]
        for key, r in res["renderers"].items():
            if key == "cycles":
                continue
            cells = []
            for mine, theirs in zip(r["spp"], cycles_rows):
                ok = mine["efficiency_sphere"] and theirs["efficiency_sphere"]
                cells.append(fmt(mine["efficiency_sphere"] / theirs["efficiency_sphere"] if ok else None, ".2f"))
            lines.append("| %s | %s |" % (key, " | ".join(cells)))
        lines.append("")
    return "\n".join(lines) + "\n"


def main(argv):
    try:
        a = parse_args(argv)
        os.makedirs(a.out, exist_ok=True)
        start = time.time()
        with open("/proc/loadavg") as f:
            load_before = f.read().split()[0]
        results = [measure_scene(a, env, r) for env in a.maps for r in a.roughness]
        with open("/proc/loadavg") as f:
            load_after = f.read().split()[0]
        note = "Load average %s before and %s after the run (%d cores)." % (load_before, load_after,
                                                                         os.cpu_count() or 0)
        summary = {"command": ["scripts/cycles-compare.sh"] + argv, "size": a.size, "spp": a.spp, "seeds": a.seeds,
                   "ref_spp": a.ref_spp, "threads": a.threads, "envpis_sampler": a.sampler,
                   "cycles_pattern": a.pattern, "ortho_height": ORTHO_HEIGHT, "loadavg": [load_before, load_after],
                   "relmse_definition": "mean over pixels of mean over RGB of (I-R)^2/(R^2+0.01), R = the renderer's "
                                        "own reference; median over seeds",
                   "efficiency_definition": "1/(relMSE x spp x seconds_per_spp), seconds_per_spp from the fastest seed "
                                            "at the largest spp",
                   "scenes": results, "wall_seconds": time.time() - start}
        with open(os.path.join(a.out, "results.json"), "w") as f:
            json.dump(summary, f, indent=1)
        md = markdown(a, results, note)
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
