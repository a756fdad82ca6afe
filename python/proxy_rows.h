// SPDX-License-Identifier: Apache-2.0
// BSDF proxies as rows of seven floats for the batched calls: a proxy row is BsdfProxy's fields in
// declaration order (PROXY_FIELDS), exactly the struct the add_* calls accumulate.
#pragma once

#include <envpis/bsdf_proxy.h>

#include "arrays.h"

namespace envpis_py {

constexpr py::ssize_t kProxyFloats = 7;
static_assert(sizeof(envpis::BsdfProxy) == kProxyFloats * sizeof(float), "BsdfProxy is seven floats");

/// The field names, in column order.
extern const char* const kProxyFields[kProxyFloats];

/// One proxy as 7 numbers.
py::array_t<float> proxy_array(const envpis::BsdfProxy& p);

/// Proxies from an N x 7 array, a structured array with (at least) the seven named fields, a list of
/// BsdfProxy, or one BsdfProxy / 7 numbers shared by every point. ValueError otherwise.
RowInput proxy_rows(py::handle obj);

/// One proxy: a BsdfProxy or 7 numbers; ValueError otherwise.
envpis::BsdfProxy one_proxy(py::handle obj);

inline envpis::BsdfProxy proxy_from_row(const float* r) {
  envpis::BsdfProxy p;
  p.diffuse = r[0], p.translucent = r[1], p.reflection = r[2], p.refraction = r[3];
  p.alpha_reflection = r[4], p.alpha_refraction = r[5], p.ior = r[6];
  return p;
}

inline void proxy_to_row(const envpis::BsdfProxy& p, float* r) {
  r[0] = p.diffuse, r[1] = p.translucent, r[2] = p.reflection, r[3] = p.refraction;
  r[4] = p.alpha_reflection, r[5] = p.alpha_refraction, r[6] = p.ior;
}

}  // namespace envpis_py
