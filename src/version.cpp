// SPDX-License-Identifier: Apache-2.0
// envpis::version(): the version compiled into the library, to detect headers and a library of
// different installations (envpis/version.h).
#include "envpis/version.h"

namespace envpis {

const char* version() noexcept { return ENVPIS_VERSION_STRING; }

}  // namespace envpis
