// SPDX-License-Identifier: Apache-2.0
// The images of `envpis compare` under DIR/images: every render as float OpenEXR and as a tonemapped
// PNG, each measured render's false-colour error map, and the object-id AOV.
#pragma once
#ifdef ENVPIS_HAVE_RENDER

#include "compare_session.h"
#include "compare_steps.h"

namespace envpis::app {

/// The error maps' range: log10 of the per-pixel relative squared error from kErrLog10Min (the
/// colormap's dark end) to kErrLog10Max (its bright end).
constexpr double kErrLog10Min = -5.0, kErrLog10Max = 1.0;

/// Exposure k of the PNGs' curve 1 - exp(-k x), from the reference: its median (R+G+B)/3 over object
/// pixels (every pixel when no object is seen) maps to 0.5 (a smooth shoulder keeps the sun's
/// reflections from clipping flat).
double tonemap_exposure(const Reference& ref);

/// reference.{exr,png}, object-id.exr, and <stem>.exr, <stem>.png, <stem>-error.png of every measured
/// render, into session.settings.out / "images".
void write_images(const CompareSession& session, const Comparison& c, double exposure);

}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
