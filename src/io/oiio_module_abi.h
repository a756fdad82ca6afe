// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal: the C interface between envpis::io and its OpenImageIO module (libenvpis_oiio.so).
//
// envpis::io does not link OpenImageIO: loading its ~260 shared libraries costs every process about half
// a second before main(), while nearly every file envpis touches is OpenEXR or PNG, which OpenEXR and
// libpng read directly. The module is loaded with dlopen the first time another format is read or
// written. Plain C types only, so that the module and the library agree whatever each was built with.
#include <cstddef>

extern "C" {

/// Bumped on any change to the structs or the functions below; the loader refuses another version.
#define ENVPIS_OIIO_MODULE_ABI 1

struct EnvpisOiioImage {
  int width;
  int height;
  int channels;       // channels read: min(stored, max_channels)
  int integer_coded;  // 1 when the file stores integers (values are code / max code)
  float* pixels;      // width * height * channels, row after row; freed with EnvpisOiioApi::release
};

/// Limits checked on the header before any pixel is read or buffer allocated.
struct EnvpisOiioLimits {
  int max_channels;         // read channels [0, max_channels) only
  std::size_t max_texels;   // width * height
  int max_side;             // width and height; 0: no limit
};

struct EnvpisOiioApi {
  int abi;  // ENVPIS_OIIO_MODULE_ABI
  /// Reads an image with OpenImageIO's reader for `format` alone (never its try-every-reader fallback).
  /// bytes != nullptr: decodes size bytes from memory. Returns 0, or -1 with a one-line reason in error.
  int (*read)(const char* path, const char* format, const void* bytes, std::size_t size,
              const EnvpisOiioLimits* limits, EnvpisOiioImage* out, char* error, std::size_t error_size);
  void (*release)(float* pixels);
  /// Writes float pixels in the format of path's extension. Returns 0, or -1 with a one-line reason.
  int (*write)(const char* path, int width, int height, int channels, const float* pixels, char* error,
               std::size_t error_size);
  /// OpenImageIO's reader for a file extension without the dot ("hdr"), or "" when none.
  const char* (*format_for_extension)(const char* extension);
};

/// The module's one exported symbol.
typedef const EnvpisOiioApi* (*EnvpisOiioEntry)(void);
#define ENVPIS_OIIO_MODULE_ENTRY "envpis_oiio_module"
}
