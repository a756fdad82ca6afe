#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Issue 21's sphere measurement for two envpis builds: relMSE on the GGX alpha 0.25 sphere (all its
pixels and the brightest quartile by reference brightness), nearest look-ups, direct light, medians over
seeds 1-3 at 16 / 64 / 256 spp, on sunrise's sun alone (its 53 brightest texels on black, written as a
PFM) and on all of sunrise. Both builds are measured against one reference (mis, 4096 spp, the first
build): the table change does not move the converged image. docs/cycles.md has the results.

  /usr/bin/python3 scripts/sun_sphere.py OLD_ENVPIS NEW_ENVPIS [OUT_DIR]   (SIZE=128 REF=4096 STRATS=env,mis)

OLD_ARGS / NEW_ARGS add options to each build's render command (e.g. NEW_ARGS='--fine-texels map', with
the same binary for both builds), OLD_SAMPLER / NEW_SAMPLER set each one's --sampler (default sobol); MAPS=sun,sunrise,nosun picks the maps (nosun: sunrise with its sun black).
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cycles_compare as cc  # noqa: E402  (its EXR reader, scene and render command)
import cycles_metrics as cm  # noqa: E402  (the sphere mask and the per-pixel error)

SUNRISE = "/usr/share/blender/datafiles/studiolights/world/sunrise.exr"


def write_sun_only(path, without_sun=False):
    img, _ = cc.read_exr(SUNRISE)
    idx = np.argsort(img.mean(axis=2).ravel())[::-1][:53]
    if without_sun:
        out = img.astype(np.float32).copy()
        out.reshape(-1, 3)[idx] = 0
    else:
        out = np.zeros_like(img, dtype=np.float32)
        out.reshape(-1, 3)[idx] = img.reshape(-1, 3)[idx]
    h, w, _ = out.shape
    with open(path, "wb") as f:  # PFM: little-endian (negative scale), rows bottom to top
        f.write(b"PF\n%d %d\n-1.0\n" % (w, h))
        f.write(np.ascontiguousarray(out[::-1]).astype("<f4").tobytes())


class Args:
    reuse, sampler, threads = True, "sobol", 2


def main(argv):
    out_dir = argv[3] if len(argv) > 3 else "out/sun-sphere"
    os.makedirs(out_dir, exist_ok=True)
    builds = {}
    for name, exe in (("old", argv[1]), ("new", argv[2])):
        extra = os.environ.get(name.upper() + "_ARGS", "")
        if extra:  # a wrapper that appends the options (the render helper takes a bare executable)
            wrapper = os.path.join(out_dir, name + "-envpis.sh")
            with open(wrapper, "w") as f:
                f.write('#!/bin/sh\nexec %s "$@" %s\n' % (os.path.abspath(exe), extra))
            os.chmod(wrapper, 0o755)
            exe = wrapper
        builds[name] = exe
    # OLD_SAMPLER / NEW_SAMPLER: each build's --sampler (default sobol)
    samplers = {n: os.environ.get(n.upper() + "_SAMPLER", "sobol") for n in builds}
    size = int(os.environ.get("SIZE", 128))
    sun = os.path.join(out_dir, "sun.pfm")
    if not os.path.exists(sun):
        write_sun_only(sun)
    nosun = os.path.join(out_dir, "nosun.pfm")
    if not os.path.exists(nosun):
        write_sun_only(nosun, without_sun=True)
    maps = {"sun": sun, "sunrise": SUNRISE, "nosun": nosun}
    scene = os.path.join(out_dir, "scene.json")
    cc.scene_json(scene, size, 0.25)
    mask = cm.sphere_mask(size)

    def render(build, env, strat, spp, seed, name):
        a = Args()
        a.envpis = builds[build]
        a.sampler = samplers[build]
        out = os.path.join(out_dir, name + ".exr")
        cc.envpis_render(a, scene, env, strat, spp, seed, out)
        return cc.read_exr(out)[0]

    for env_name in os.environ.get("MAPS", "sun,sunrise").split(","):
        env = maps[env_name]
        ref = render("old", env, "mis", int(os.environ.get("REF", 4096)), 99, env_name + "-ref")
        lum = ref.mean(axis=2)
        edges = np.percentile(lum[mask], [25, 50, 75])
        top = mask & (lum >= edges[2])
        darker = [mask & (lum < edges[0]), mask & (lum >= edges[0]) & (lum < edges[1]),
                  mask & (lum >= edges[1]) & (lum < edges[2])]
        for strat in os.environ.get("STRATS", "env,mis").split(","):
            for b in builds:
                row = []
                for spp in (16, 64, 256):
                    errs = [cm.rel_sq_error(render(b, env, strat, spp, s, "%s-%s-%s-%d-%d" % (env_name, strat, b, spp, s)), ref)
                            for s in (1, 2, 3)]
                    row.append((np.median([e[mask].mean() for e in errs]), np.median([e[top].mean() for e in errs]),
                                [np.median([e[q].mean() for e in errs]) for q in darker]))
                slope = np.polyfit(np.log([16, 64, 256]), np.log([r[0] for r in row]), 1)[0]
                print("%s %s %s relMSE 16/64/256: %s slope %.2f | brightest quartile: %s | quartiles 1-3 at 256: %s" % (
                    env_name, strat, b, " / ".join("%.3g" % r[0] for r in row), slope,
                    " / ".join("%.3g" % r[1] for r in row), " / ".join("%.3g" % v for v in row[-1][2])), flush=True)


if __name__ == "__main__":
    main(sys.argv)
