#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Batched product sampling from Python against the same loop in C++.

    PYTHONPATH=build/python python3 python/bench_batch.py [--points 1000000] [--repeats 5]

Makes N random shading points (normal, wo, a mixed proxy, u) on Blender's sunset.exr, times
envpis.product_sample (prepare + one sample per point) on one thread and on all cores, and runs
envpis_batch_loop (python/bench_batch_loop.cpp, built next to the module) on the same inputs: the same
loop in C++ with no Python. Prints the best ns per shading point of each (wall, and process CPU time,
which is what counts on a shared machine), and the ratio Python / C++.
Also checks that both produced the same pdfs.
"""
import argparse
import os
import subprocess
import tempfile
import time

import numpy as np

import envpis

SUNSET = "/usr/share/blender/datafiles/studiolights/world/sunset.exr"


def shading_points(n, seed=1):
    rng = np.random.default_rng(seed)
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    wo = rng.normal(size=(n, 3))
    wo *= np.sign(np.sum(wo * normals, axis=1))[:, None]  # on the normal's side
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    proxies = np.zeros((n, 7))
    proxies[:, 0] = rng.random(n)          # diffuse
    proxies[:, 2] = rng.random(n)          # reflection
    proxies[:, 3] = rng.random(n) * (rng.random(n) < 0.25)  # refraction on a quarter of the points
    proxies[:, 4] = rng.random(n)          # alpha_reflection
    proxies[:, 5] = rng.random(n)          # alpha_refraction
    proxies[:, 6] = 1.5
    u = rng.random((n, 2))
    return [a.astype(np.float32) for a in (normals, wo, proxies, u)]


def timed(n, run):
    """Wall and process-CPU ns per point of run() (the CPU time of a one-thread run is its cost on a
    machine shared with other jobs), and its result."""
    t0, c0 = time.perf_counter(), time.process_time()
    result = run()
    cpu, wall = time.process_time() - c0, time.perf_counter() - t0
    return {"wall": wall / n * 1e9, "cpu": cpu / n * 1e9}, result


def best_of(best, timing):
    return timing if best is None else {k: min(best[k], timing[k]) for k in timing}

def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--map", default=SUNSET)
    p.add_argument("--points", type=int, default=1_000_000)
    p.add_argument("--repeats", type=int, default=5)
    default_loop = os.path.join(os.path.dirname(envpis.__file__), "envpis_batch_loop")
    p.add_argument("--loop", default=default_loop, help="the C++ loop executable")
    args = p.parse_args()

    n = args.points
    normals, wo, proxies, u = shading_points(n)
    table = envpis.ImportanceTable(envpis.EnvironmentMap.load(args.map))
    f64 = [a.astype(np.float64) for a in (normals, wo, proxies, u)]
    # Rounds alternate C++ and Python, so that both see the same load on a shared machine.
    cpp = py_serial = py_parallel = py_f64 = None
    with tempfile.TemporaryDirectory() as tmp:
        for name, a in (("normals", normals), ("wo", wo), ("proxies", proxies), ("u", u)):
            a.tofile(os.path.join(tmp, name + ".f32"))
        for _ in range(args.repeats):
            out = subprocess.run([args.loop, args.map, tmp, str(n), "1"], check=True,
                                 capture_output=True, text=True).stdout
            cpp = best_of(cpp, dict((k, float(v)) for k, v in (line.split() for line in out.splitlines())))
            t, (_, pdf_py) = timed(n, lambda: envpis.product_sample(table, normals, wo, proxies, u, threads=1))
            py_serial = best_of(py_serial, t)
            py_parallel = best_of(py_parallel, timed(n, lambda: envpis.product_sample(table, normals, wo, proxies, u))[0])
            py_f64 = best_of(py_f64, timed(n, lambda: envpis.product_sample(table, *f64))[0])
        pdf_cpp = np.fromfile(os.path.join(tmp, "pdf_cpp.f32"), dtype=np.float32)
    assert np.array_equal(pdf_py, pdf_cpp), "Python and C++ pdfs differ"

    print(f"{n:,} shading points, prepare + 1 sample each, best of {args.repeats}, simd {envpis.simd_name()}, "
          f"{os.cpu_count()} cores; ns per shading point")
    print(f"{'':22} {'Python':>8} {'C++':>8} {'ratio':>6}")
    rows = (("one thread, CPU", py_serial["cpu"], cpp["serial_cpu"]),
            ("one thread, wall", py_serial["wall"], cpp["serial_wall"]),
            ("all cores, wall", py_parallel["wall"], cpp["parallel_wall"]),
            ("all cores, CPU", py_parallel["cpu"], cpp["parallel_cpu"]))
    for name, py, c in rows:
        print(f"{name:22} {py:8.1f} {c:8.1f} {py / c:6.2f}")
    print(f"{'all cores, float64 in':22} {py_f64['wall']:8.1f} (wall; inputs converted to float32)")

if __name__ == "__main__":
    main()
