// SPDX-License-Identifier: Apache-2.0
// Internal to the scene-file reader (render/scene_file.cpp): typed access to one JSON object of a
// scene file, whose errors name the file and the field's path, and which rejects unknown fields.
#pragma once

#include <cmath>
#include <set>
#include <sstream>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "envpis/common.h"

namespace envpis::render::detail {

/// Typed access to a JSON object with errors that name the file and the field's path.
class Fields {
 public:
  Fields(const nlohmann::json& j, std::string path, const std::string* file) : j_(j), path_(std::move(path)), file_(file) {
    if (!j.is_object()) fail("expected an object");
  }

  [[noreturn]] void fail(const std::string& what) const { fail_at(path_, what); }
  [[noreturn]] void fail_at(const std::string& path, const std::string& what) const {
    throw Error(*file_ + ": " + (path.empty() ? std::string("(top level)") : path) + ": " + what);
  }
  std::string sub(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  bool has(const std::string& key) const {
    used_.insert(key);
    return j_.contains(key);
  }
  const nlohmann::json& get(const std::string& key) const {
    used_.insert(key);
    if (!j_.contains(key)) fail("missing field '" + key + "'");
    return j_.at(key);
  }
  Fields object(const std::string& key) const { return Fields(get(key), sub(key), file_); }

  float number(const std::string& key) const {
    const nlohmann::json& v = get(key);
    if (!v.is_number()) fail_at(sub(key), "expected a number");
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail_at(sub(key), "expected a finite number");
    return static_cast<float>(d);
  }
  float number(const std::string& key, float def) const { return has(key) ? number(key) : def; }
  float number_in(const std::string& key, float def, float lo, float hi) const {
    const float v = number(key, def);
    if (!(v >= lo && v <= hi))
      fail_at(sub(key), "must be in [" + fmt(lo) + ", " + fmt(hi) + "], got " + fmt(v));
    return v;
  }
  int integer(const std::string& key, int def, int lo, int hi) const {
    if (!has(key)) return def;
    const nlohmann::json& v = get(key);
    if (!v.is_number_integer()) fail_at(sub(key), "expected an integer");
    const long long x = v.get<long long>();
    if (x < lo || x > hi) fail_at(sub(key), "must be in " + std::to_string(lo) + ".." + std::to_string(hi));
    return static_cast<int>(x);
  }
  bool boolean(const std::string& key, bool def) const {
    if (!has(key)) return def;
    const nlohmann::json& v = get(key);
    if (!v.is_boolean()) fail_at(sub(key), "expected true or false");
    return v.get<bool>();
  }
  std::string string(const std::string& key) const {
    const nlohmann::json& v = get(key);
    if (!v.is_string()) fail_at(sub(key), "expected a string");
    return v.get<std::string>();
  }
  std::string string(const std::string& key, const std::string& def) const { return has(key) ? string(key) : def; }
  Vec3 vec3(const std::string& key) const {
    const nlohmann::json& v = get(key);
    if (!v.is_array() || v.size() != 3) fail_at(sub(key), "expected an array of 3 numbers");
    float c[3];
    for (int i = 0; i < 3; ++i) {
      if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) fail_at(sub(key), "expected an array of 3 numbers");
      c[i] = v[i].get<float>();
    }
    return {c[0], c[1], c[2]};
  }
  Vec3 vec3(const std::string& key, Vec3 def) const { return has(key) ? vec3(key) : def; }
  /// A colour: a number (grey) or [r, g, b], each in [lo, hi].
  Rgb color(const std::string& key, Rgb def, float lo = 0.0f, float hi = 1.0f) const {
    if (!has(key)) return def;
    const nlohmann::json& v = get(key);
    Rgb c;
    if (v.is_number()) {
      const float g = v.get<float>();
      c = {g, g, g};
    } else if (v.is_array() && v.size() == 3 && v[0].is_number() && v[1].is_number() && v[2].is_number()) {
      c = {v[0].get<float>(), v[1].get<float>(), v[2].get<float>()};
    } else {
      fail_at(sub(key), "expected a number or an array of 3 numbers");
    }
    for (float x : {c.r, c.g, c.b})
      if (!(x >= lo && x <= hi)) fail_at(sub(key), "components must be in [" + fmt(lo) + ", " + fmt(hi) + "]");
    return c;
  }
  /// Rejects fields that were never read (typos).
  void finish() const {
    for (auto it = j_.begin(); it != j_.end(); ++it)
      if (!used_.count(it.key())) fail("unknown field '" + it.key() + "'");
  }
  const std::string& path() const { return path_; }
  const std::string& file() const { return *file_; }

 private:
  static std::string fmt(float v) {
    std::ostringstream s;
    s << v;
    return s.str();
  }
  const nlohmann::json& j_;
  std::string path_;
  const std::string* file_;
  mutable std::set<std::string> used_;
};

}  // namespace envpis::render::detail
