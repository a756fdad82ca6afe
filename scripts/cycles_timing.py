#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
# Cost per sample of envpis builds against Cycles on the matched spheres of scripts/cycles-compare.sh,
# timed in one run with the renders interleaved (the machines here drift by 30% within an hour, so
# only figures from one run are compared). No references, no errors: scripts/cycles-compare.sh
# measures those.
#
#   /usr/bin/python3 scripts/cycles_timing.py [--rounds 5] [--maps sunrise,studio,courtyard] [--alphas 0.04,0.25]
#       [--size 128] [--spp 256] [--threads 2] [--strategies mis,product] [BINARY ...]
#
# BINARY: envpis binaries to compare (default build/apps/envpis/envpis). Per scene it prints the
# medians over the rounds: Cycles' sampling time (its EXR's render_time) and each binary's render
# loop (its wall seconds, which leave out the tables), as ms per spp, and the ratios. Exit 1 with one line on
# any failure. Debian's python3 (numpy, as scripts/cycles-compare.sh).
import argparse
import os
import statistics
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import cycles_compare as C  # noqa: E402  (the scene file, both renders and the EXR reader, written once)


def envpis_ms(binary, scene, env, strategy, a, out):
    # cycles_compare's own render (its --reuse off), wall seconds of the sampling loop without the tables
    opts = argparse.Namespace(reuse=False, envpis=binary, sampler="sobol", threads=a.threads)
    return C.envpis_render(opts, scene, env, strategy, a.spp, 1, out) * 1000 / a.spp


def cycles_ms(env, alpha, a, out):
    opts = argparse.Namespace(reuse=False, blender=a.blender, size=a.size, threads=a.threads,
                              pattern="PROGRESSIVE_MULTI_JITTER")
    C.cycles_renders(opts, env, alpha ** 0.5, [(a.spp, 1, out)])
    _, header = C.read_exr(out)
    return C.blender_seconds(header, out) * 1000 / a.spp


def main():
    p = argparse.ArgumentParser(description="ms per spp of envpis builds against Cycles, interleaved")
    p.add_argument("binaries", nargs="*", default=[os.path.join(REPO, "build", "apps", "envpis", "envpis")])
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--maps", default="sunrise,studio,courtyard")
    p.add_argument("--alphas", default="0.04,0.25")
    p.add_argument("--size", type=int, default=128)
    p.add_argument("--spp", type=int, default=256)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--strategies", default="mis,product")
    p.add_argument("--blender", default="blender")
    a = p.parse_args()
    if a.rounds < 1 or a.size < 1 or a.spp < 1 or a.threads < 1:
        raise C.Failure("--rounds, --size, --spp and --threads must be positive")
    strategies = a.strategies.split(",")
    with tempfile.TemporaryDirectory() as tmp:
        for name in a.maps.split(","):
            env = os.path.join(C.STUDIOLIGHTS, name + ".exr")
            if not os.path.isfile(env):
                raise C.Failure("no map '%s' (Debian's blender-data)" % env)
            for alpha in (float(x) for x in a.alphas.split(",")):
                scene = os.path.join(tmp, "scene.json")
                C.scene_json(scene, a.size, alpha)
                times = {}
                for _ in range(a.rounds):
                    times.setdefault("cycles", []).append(cycles_ms(env, alpha, a, os.path.join(tmp, "c.exr")))
                    for i, b in enumerate(a.binaries):
                        for s in strategies:
                            ms = envpis_ms(b, scene, env, s, a, os.path.join(tmp, "e.exr"))
                            times.setdefault((i, s), []).append(ms)
                med = {k: statistics.median(v) for k, v in times.items()}
                line = "%s %g: Cycles %.2f ms/spp" % (name, alpha, med["cycles"])
                for i, b in enumerate(a.binaries):
                    parts = ["%s %.2f (%.2fx Cycles)" % (s, med[(i, s)], med[(i, s)] / med["cycles"]) for s in strategies]
                    line += " | %s: %s" % (os.path.relpath(b), ", ".join(parts))
                print(line, flush=True)


if __name__ == "__main__":
    try:
        main()
    except C.Failure as e:
        print("cycles_timing.py: %s" % e, file=sys.stderr)
        sys.exit(1)
