// SPDX-License-Identifier: Apache-2.0
// The options of `envpis table`: as typed (TableArgs, registered on the subcommand), and checked
// (TableSettings), every error one line naming its option, all before anything slow.
#pragma once

#include <CLI/CLI.hpp>

#include <filesystem>
#include <string>

#include "envpis/envpis.h"

namespace envpis::app {

struct TableArgs {
  std::string env, out;
  std::string layout = "auto";
  std::string rotate = "0", scale = "1";
  std::string orientation = "panorama", filter = "bilinear";
  std::string top = "12", fine = "0", peak_ratio = "8";
  std::string normal = "0,0,1", wo = "1,0,1";
  std::string proxy;  // empty: reflection=1, alpha_r=0.2
  std::string transform, min_alpha, max_alpha, env_mix = "0";
  std::string samples = "1000", seed = "1";
};

struct TableSettings {
  std::string env;
  std::filesystem::path out;
  EnvironmentMapOptions map_options;
  float rotate_degrees = 0;
  ImportanceTableOptions table_options;
  Vec3 normal, wo;  // unit vectors
  BsdfProxy proxy;
  ProductSamplerOptions sampler_options;
  long long samples = 0;
  unsigned long long seed = 0;
};

/// Adds --env, --out, --layout, ... to `sub`, bound to `a`.
void add_table_options(CLI::App& sub, TableArgs& a);
/// Checks every option and creates the output directory (throws Error naming the option or the
/// directory).
TableSettings parse_table_args(const TableArgs& a);

}  // namespace envpis::app
