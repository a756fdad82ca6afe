// SPDX-License-Identifier: Apache-2.0
// The C++ side of python/bench_batch.py: the same batched product sampling (prepare + one sample per
// shading point) as envpis.product_sample, on the inputs the script wrote, timed without Python.
//
// usage: envpis_batch_loop MAP DIR N REPEATS
//   reads DIR/{normals,wo,proxies,u}.f32 (raw float32: N x 3, N x 3, N x 7, N x 2), builds the table
//   of MAP with default options, and for REPEATS runs times (a) one thread, one ProductSampler, and
//   (b) all cores with one ProductSampler per TBB thread. Prints the best wall and CPU ns per shading
//   point of each and writes the pdfs of the last run to DIR/pdf_cpp.f32 (the script checks they equal Python's).
#include <envpis/envpis.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

namespace {

using namespace envpis;

std::vector<float> read_floats(const std::string& path, std::size_t count) {
  std::vector<float> v(count);
  std::ifstream f(path, std::ios::binary);
  if (!f.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(count * sizeof(float))))
    throw Error("cannot read " + std::to_string(count) + " floats from " + path);
  return v;
}

struct Inputs {
  std::vector<float> n, wo, proxy, u;
};

BsdfProxy proxy_at(const float* r) {
  BsdfProxy p;
  p.diffuse = r[0], p.translucent = r[1], p.reflection = r[2], p.refraction = r[3];
  p.alpha_reflection = r[4], p.alpha_refraction = r[5], p.ior = r[6];
  return p;
}

// One shading point: prepare, draw one sample, store its direction and pdf (as the binding does).
void shade(ProductSampler& s, const Inputs& in, std::size_t i, float* dirs, float* pdf) {
  const float *n = &in.n[3 * i], *wo = &in.wo[3 * i];
  s.prepare({n[0], n[1], n[2]}, {wo[0], wo[1], wo[2]}, proxy_at(&in.proxy[7 * i]));
  const DirectionSample d = s.sample({in.u[2 * i], in.u[2 * i + 1]});
  dirs[3 * i] = d.direction.x, dirs[3 * i + 1] = d.direction.y, dirs[3 * i + 2] = d.direction.z;
  pdf[i] = d.pdf;
}

struct Timing {
  double wall_ns = 1e300, cpu_ns = 1e300;  // best per shading point over the repeats
};

// Wall time, and the process's CPU time: on a machine shared with other jobs the CPU time of a
// one-thread run is what the loop costs, whatever the others do.
template <class F>
Timing best_ns_per_point(int repeats, std::size_t n, F run) {
  Timing best;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    run();
    const double cpu = double(std::clock() - c0) / CLOCKS_PER_SEC * 1e9;
    const std::chrono::duration<double, std::nano> dt = std::chrono::steady_clock::now() - t0;
    best.wall_ns = std::min(best.wall_ns, dt.count() / static_cast<double>(n));
    best.cpu_ns = std::min(best.cpu_ns, cpu / static_cast<double>(n));
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: %s MAP DIR N REPEATS\n", argv[0]);
    return 2;
  }
  try {
    const std::string dir = argv[2];
    const std::size_t n = std::stoul(argv[3]);
    const int repeats = std::stoi(argv[4]);
    const EnvironmentMap map = EnvironmentMap::load(argv[1]);
    const ImportanceTable table(map);
    const Inputs in{read_floats(dir + "/normals.f32", 3 * n), read_floats(dir + "/wo.f32", 3 * n),
                    read_floats(dir + "/proxies.f32", 7 * n), read_floats(dir + "/u.f32", 2 * n)};
    std::vector<float> dirs(3 * n), pdf(n);

    const Timing serial = best_ns_per_point(repeats, n, [&] {
      ProductSampler s(table);
      for (std::size_t i = 0; i < n; ++i) shade(s, in, i, dirs.data(), pdf.data());
    });
    const Timing parallel = best_ns_per_point(repeats, n, [&] {
      tbb::enumerable_thread_specific<ProductSampler> samplers([&] { return ProductSampler(table); });
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
        ProductSampler& s = samplers.local();
        for (std::size_t i = r.begin(); i != r.end(); ++i) shade(s, in, i, dirs.data(), pdf.data());
      });
    });
    std::ofstream(dir + "/pdf_cpp.f32", std::ios::binary)
        .write(reinterpret_cast<const char*>(pdf.data()), static_cast<std::streamsize>(n * sizeof(float)));
    std::printf("serial_wall %.2f\nserial_cpu %.2f\nparallel_wall %.2f\nparallel_cpu %.2f\n", serial.wall_ns,
                serial.cpu_ns, parallel.wall_ns, parallel.cpu_ns);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "envpis_batch_loop: %s\n", e.what());
    return 1;
  }
  return 0;
}
