// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal: envpis::io's handle on its OpenImageIO module (oiio_module_abi.h says why it is a module).
#include <string>

#include "oiio_module_abi.h"

namespace envpis::detail {

/// The module's functions, loaded on the first call (thread-safe) and kept for the process's life.
/// Looked for at $ENVPIS_OIIO_MODULE if set, else where the build put it, else where `cmake --install`
/// puts it. Throws envpis::Error with a one-line reason (where it looked) when it cannot be loaded.
const EnvpisOiioApi& oiio_module();

/// The path oiio_module() loaded or would load first; for messages and tests.
std::string oiio_module_path();

}  // namespace envpis::detail
