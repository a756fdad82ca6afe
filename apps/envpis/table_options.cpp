// SPDX-License-Identifier: Apache-2.0
#include "table_options.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <system_error>
#include <vector>

#include "options.h"

namespace envpis::app {
namespace {

namespace fs = std::filesystem;

Vec3 parse_vec3(const std::string& option, const std::string& text) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (;;) {
    const std::size_t comma = text.find(',', start);
    parts.push_back(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (parts.size() != 3)
    throw Error(option + ": expected three comma-separated numbers x,y,z, got '" + text + "'");
  float c[3];
  for (int i = 0; i < 3; ++i) {
    double v = 0;
    try {
      v = parse_number(option, parts[i]);
    } catch (const Error&) {
      throw Error(option + ": expected three comma-separated finite numbers x,y,z, got '" + text + "'");
    }
    if (std::fabs(v) > 1e30) throw Error(option + ": component out of range in '" + text + "'");
    c[i] = static_cast<float>(v);
  }
  const Vec3 v{c[0], c[1], c[2]};
  if (!is_valid_direction(v)) throw Error(option + ": the vector must be non-zero, got '" + text + "'");
  return normalize(v);
}

// --proxy key=value,... : unmentioned weights are 0, roughnesses 0.2, ior 1.5.
BsdfProxy parse_proxy(const std::string& text) {
  BsdfProxy p;
  p.alpha_reflection = p.alpha_refraction = 0.2f;
  p.ior = 1.5f;
  if (text.empty()) {
    p.reflection = 1.0f;
    return p;
  }
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos)
      throw Error("--proxy: expected key=value, got '" + item + "' (keys: diffuse, translucent, reflection, "
                  "refraction, alpha_r, alpha_t, ior)");
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    const std::string opt = "--proxy " + key;
    if (key == "diffuse") {
      p.diffuse = float(parse_number_in(opt, value, 0, 1e6, ">= 0"));
    } else if (key == "translucent") {
      p.translucent = float(parse_number_in(opt, value, 0, 1e6, ">= 0"));
    } else if (key == "reflection") {
      p.reflection = float(parse_number_in(opt, value, 0, 1e6, ">= 0"));
    } else if (key == "refraction") {
      p.refraction = float(parse_number_in(opt, value, 0, 1e6, ">= 0"));
    } else if (key == "alpha_r") {
      p.alpha_reflection = float(parse_number_in(opt, value, 0, 1, "in [0, 1]"));
    } else if (key == "alpha_t") {
      p.alpha_refraction = float(parse_number_in(opt, value, 0, 1, "in [0, 1]"));
    } else if (key == "ior") {
      p.ior = float(parse_number_in(opt, value, 1e-3, 1e3, "in [0.001, 1000]"));
    } else {
      throw Error("--proxy: unknown key '" + key +
                  "' (keys: diffuse, translucent, reflection, refraction, alpha_r, alpha_t, ior)");
    }
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return p;
}

// Creates DIR (and parents) and checks that a file can be written in it.
void prepare_output_dir(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw Error("cannot create output directory '" + dir + "': " + ec.message());
  if (!fs::is_directory(dir, ec)) throw Error("output path '" + dir + "' exists and is not a directory");
  const fs::path probe = fs::path(dir) / ".envpis-write-test";
  {
    std::ofstream f(probe);
    if (!f || !(f << "x") || !(f.flush()))
      throw Error("cannot write to output directory '" + dir + "': " + std::strerror(errno));
  }
  fs::remove(probe, ec);
}

ProductSamplerOptions parse_sampler_options(const TableArgs& a) {
  ProductSamplerOptions o;
  if (!a.transform.empty())
    o.proxy.transform = with_option("--transform", [&] { return parse_roughness_transform(a.transform); });
  if (!a.min_alpha.empty()) o.proxy.min_alpha = float(parse_number_in("--min-alpha", a.min_alpha, 0, 1, "in [0, 1]"));
  if (!a.max_alpha.empty()) o.proxy.max_alpha = float(parse_number_in("--max-alpha", a.max_alpha, 0, 1, "in [0, 1]"));
  o.env_mix = float(parse_number_in("--env-mix", a.env_mix, 0, 1, "in [0, 1]"));
  return o;
}

}  // namespace

TableSettings parse_table_args(const TableArgs& a) {
  if (a.env.empty()) throw Error("--env FILE is required");
  if (a.out.empty()) throw Error("--out DIR is required");
  TableSettings s;
  s.env = a.env;
  s.out = a.out;
  s.map_options.layout = with_option("--layout", [&] { return parse_map_layout(a.layout); });
  s.rotate_degrees = float(parse_number_in("--rotate", a.rotate, -1e6, 1e6, "in [-1e6, 1e6] degrees"));
  s.map_options.rotation = Mat3::rotate_z(s.rotate_degrees);
  s.map_options.scale = float(parse_number_in("--scale", a.scale, 0, 1e30, ">= 0"));
  s.map_options.orientation =
      with_option("--env-orientation", [&] { return parse_latlong_orientation(a.orientation); });
  s.map_options.filter = with_option("--env-filter", [&] { return parse_map_filter(a.filter); });
  s.table_options.top_resolution = int(parse_integer("--top", a.top, 1, 256));
  s.table_options.fine_resolution = int(parse_integer("--fine", a.fine, 0, 16384));
  s.table_options.peak_ratio = parse_peak_ratio(a.peak_ratio);
  s.normal = parse_vec3("--normal", a.normal);
  s.wo = parse_vec3("--wo", a.wo);
  s.proxy = parse_proxy(a.proxy);
  s.sampler_options = parse_sampler_options(a);
  s.samples = parse_integer("--samples", a.samples, 1, 10000000);
  s.seed = static_cast<unsigned long long>(parse_integer("--seed", a.seed, 0, 1LL << 62));
  prepare_output_dir(a.out);
  return s;
}

void add_table_options(CLI::App& sub, TableArgs& a) {
  sub.add_option("--env", a.env, "Environment map (OpenEXR, Radiance HDR, ...) (required)")->type_name("FILE");
  sub.add_option("--out", a.out, "Output directory, created if needed (required)")->type_name("DIR");
  sub.add_option("--layout", a.layout, "Map layout: auto, latlong or equal-area (default auto)")->type_name("L");
  sub.add_option("--rotate", a.rotate, "Rotate the map about +Z (up) by DEG degrees (default 0)")->type_name("DEG");
  sub.add_option("--scale", a.scale, "Multiply the map's radiance by S >= 0 (default 1)")->type_name("S");
  sub.add_option("--env-orientation", a.orientation,
                 "Lat-long column direction: panorama (Blender/Cycles: +X at the centre column) or legacy "
                 "(+X at the left edge, mirrored) (default panorama)")
      ->type_name("O");
  sub.add_option("--env-filter", a.filter, "Radiance look-up: bilinear or nearest (default bilinear)")->type_name("F");
  sub.add_option("--top", a.top, "Top-level resolution T, 1..256 (default 12)")->type_name("T");
  sub.add_option("--fine", a.fine, "Fine resolution N (rounded up to a multiple of T); 0 = from the map's "
                                   "texel count (default)")
      ->type_name("N");
  sub.add_option("--peak-ratio", a.peak_ratio,
                 "Each texel's importance is at least 1/K of the radiance the look-up reaches in it; 0 = off "
                 "(default 8)")
      ->type_name("K");
  sub.add_option("--normal", a.normal, "Shading normal (default 0,0,1)")->type_name("x,y,z");
  sub.add_option("--wo", a.wo, "Outgoing direction, towards the viewer (default 1,0,1 normalized)")
      ->type_name("x,y,z");
  sub.add_option("--proxy", a.proxy,
                 "BSDF proxy: diffuse=,translucent=,reflection=,refraction= weights, alpha_r=,alpha_t= GGX "
                 "roughness, ior= (unmentioned weights 0, roughness 0.2, ior 1.5; default reflection=1)")
      ->type_name("k=v,...");
  sub.add_option("--transform", a.transform, "Proxy roughness transform: slides, abstract, hybrid or fitted (default: the "
                                             "library's)")
      ->type_name("NAME");
  sub.add_option("--min-alpha", a.min_alpha, "Floor on the transformed roughness, [0,1] (default: the "
                                             "library's)")
      ->type_name("A");
  sub.add_option("--max-alpha", a.max_alpha, "Cap on the transformed roughness, [0,1] (default: the "
                                             "library's)")
      ->type_name("A");
  sub.add_option("--env-mix", a.env_mix, "Fraction of environment-only sampling mixed in, [0,1] (default 0)")
      ->type_name("M");
  sub.add_option("--samples", a.samples, "Product samples drawn on product_samples.png (default 1000)")
      ->type_name("K");
  sub.add_option("--seed", a.seed, "Random seed (default 1)")->type_name("K");
}

}  // namespace envpis::app
