// SPDX-License-Identifier: Apache-2.0
// The OpenImageIO module (libenvpis_oiio.so): every image format but OpenEXR and PNG, behind the C
// interface of oiio_module_abi.h. Loaded by envpis::io with dlopen on first use (oiio_loader.cpp).
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <new>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "oiio_module_abi.h"

namespace {

// Header claims bounded before any pixel is read. A reader allocates its decoding buffers from the header
// (OpenEXR: up to 256 scanlines of every channel at once; TIFF: a strip of its claimed rows), so a
// 600-byte file claiming an 8M-texel-wide image must be refused here, not discovered as a multi-GB
// allocation. An 8k x 4k RGBA float map has 128 KB scanlines: the limits are 128 and 32 times that.
constexpr std::size_t kMaxScanlineBytes = std::size_t(16) << 20;  // one scanline, all channels, in the file
constexpr std::size_t kMaxTileBytes = std::size_t(64) << 20;      // one tile, all channels, in the file
constexpr std::size_t kBandBytes = std::size_t(32) << 20;         // rows decoded at a time

struct Failure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string first_line(std::string s) {
  const auto nl = s.find('\n');
  if (nl != std::string::npos) s.resize(nl);
  return s.empty() ? std::string("no detail from OpenImageIO") : s;
}

const char* display_name(const std::string& format) {
  if (format == "hdr") return "Radiance HDR";
  if (format == "pnm") return "PFM";
  if (format == "tiff") return "TIFF";
  if (format == "jpeg") return "JPEG";
  return format.c_str();
}

// Channels [0, nc) of every texel as float, row after row, read in the file's own data format a band of
// rows (or a row of tiles) at a time into a buffer sized here, and converted here: read_image() with a
// conversion to float would size its own band buffer from the header and allocate it before finding the
// data missing (12 GB for a 600-byte EXR claiming 8M x 2 texels).
void read_texels(OIIO::ImageInput& in, const OIIO::ImageSpec& spec, int nc, float* out) {
  const std::size_t width = static_cast<std::size_t>(spec.width);
  const std::size_t pixel_bytes = spec.pixel_bytes(0, nc, true);
  const std::size_t row_bytes = width * pixel_bytes;
  const int band_rows = spec.tile_width > 0
                            ? std::min(spec.tile_height, spec.height)
                            : static_cast<int>(std::clamp<std::size_t>(kBandBytes / row_bytes, 1,
                                                                       static_cast<std::size_t>(spec.height)));
  std::vector<unsigned char> band(static_cast<std::size_t>(band_rows) * row_bytes);
  for (int y = 0; y < spec.height; y += band_rows) {
    const int rows = std::min(band_rows, spec.height - y);
    const bool ok =
        spec.tile_width > 0
            ? in.read_tiles(0, 0, spec.x, spec.x + spec.width, spec.y + y, spec.y + y + rows, spec.z, spec.z + 1, 0,
                            nc, OIIO::TypeDesc::UNKNOWN, band.data())
            : in.read_scanlines(0, 0, spec.y + y, spec.y + y + rows, spec.z, 0, nc, OIIO::TypeDesc::UNKNOWN,
                                band.data());
    if (!ok) throw Failure("could not read the pixels (corrupt or truncated?): " + first_line(in.geterror()));
    float* dst = out + static_cast<std::size_t>(y) * width * nc;
    const auto dst_pixel = static_cast<OIIO::stride_t>(nc * sizeof(float));
    std::size_t offset = 0;  // of channel c within a stored pixel
    for (int c = 0; c < nc; ++c) {
      const OIIO::TypeDesc type = spec.channelformat(c);
      if (!OIIO::convert_image(1, spec.width, rows, 1, band.data() + offset, type,
                               static_cast<OIIO::stride_t>(pixel_bytes), static_cast<OIIO::stride_t>(row_bytes),
                               OIIO::AutoStride, dst + c, OIIO::TypeDesc::FLOAT, dst_pixel,
                               dst_pixel * static_cast<OIIO::stride_t>(width), OIIO::AutoStride))
        throw Failure(std::string("cannot convert texels stored as ") + type.c_str() + " to float");
      offset += type.size();
    }
  }
}

void check_header(const OIIO::ImageSpec& spec, const EnvpisOiioLimits& limits) {
  if (spec.deep) throw Failure("deep images are not supported");
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) throw Failure("the image has no pixels");
  if (spec.depth > 1) throw Failure("volume images are not supported");
  const std::string size = std::to_string(spec.width) + "x" + std::to_string(spec.height);
  const std::size_t texels = static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height);
  if (texels > limits.max_texels || (limits.max_side > 0 && std::max(spec.width, spec.height) > limits.max_side))
    throw Failure("the image is too large (" + size + ")");
  if (spec.scanline_bytes(true) > kMaxScanlineBytes)
    throw Failure("the image's scanlines are implausibly large (" + std::to_string(spec.width) + " texels of " +
                  std::to_string(spec.nchannels) + " channels, " + std::to_string(spec.scanline_bytes(true)) +
                  " bytes each; the limit is " + std::to_string(kMaxScanlineBytes) + ")");
  if (spec.tile_width > 0 && spec.tile_bytes(true) > kMaxTileBytes)
    throw Failure("the image's tiles are implausibly large (" + std::to_string(spec.tile_width) + "x" +
                  std::to_string(spec.tile_height) + " texels of " + std::to_string(spec.nchannels) + " channels)");
}

void read_image(const char* path, const std::string& format, const void* bytes, std::size_t size,
                const EnvpisOiioLimits& limits, EnvpisOiioImage& out) {
  // OIIO's IOMemReader takes a non-const pointer but only reads through it.
  OIIO::Filesystem::IOMemReader mem(const_cast<void*>(bytes), size);
  auto in = OIIO::ImageInput::create(format, false, nullptr, bytes ? &mem : nullptr);
  if (!in) throw Failure("no " + format + " reader in this OpenImageIO: " + first_line(OIIO::geterror()));
  OIIO::ImageSpec opened;
  if ((bytes && !in->set_ioproxy(&mem)) || !in->open(path, opened))
    throw Failure(std::string(display_name(format)) + " reader: " + first_line(in->geterror()));
  const OIIO::ImageSpec spec = in->spec();
  check_header(spec, limits);
  const int nc = std::min(spec.nchannels, std::max(1, limits.max_channels));
  const std::size_t values = static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height) * nc;
  float* pixels = static_cast<float*>(std::malloc(values * sizeof(float)));
  if (!pixels)
    throw Failure("not enough memory for " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                  " texels");
  try {
    read_texels(*in, spec, nc, pixels);
  } catch (...) {
    std::free(pixels);
    throw;
  }
  in->close();
  out.width = spec.width;
  out.height = spec.height;
  out.channels = nc;
  out.integer_coded = spec.format.is_floating_point() ? 0 : 1;
  out.pixels = pixels;
}

void write_image(const char* path, int width, int height, int channels, const float* pixels) {
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw Failure(first_line(OIIO::geterror()));
  const OIIO::ImageSpec spec(width, height, channels, OIIO::TypeDesc::FLOAT);
  if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, pixels) || !out->close())
    throw Failure(first_line(out->geterror()));
}

void copy_error(const char* what, char* error, std::size_t error_size) {
  if (error_size == 0) return;
  std::strncpy(error, what, error_size - 1);
  error[error_size - 1] = '\0';
}

// Every call turns every exception into a return code: none may cross the C interface.
template <class F>
int guarded(char* error, std::size_t error_size, F&& f) {
  try {
    f();
    return 0;
  } catch (const std::bad_alloc&) {
    copy_error("not enough memory", error, error_size);
  } catch (const std::exception& e) {
    copy_error(e.what(), error, error_size);
  } catch (...) {
    copy_error("unknown error in OpenImageIO", error, error_size);
  }
  return -1;
}

int module_read(const char* path, const char* format, const void* bytes, std::size_t size,
                const EnvpisOiioLimits* limits, EnvpisOiioImage* out, char* error, std::size_t error_size) {
  return guarded(error, error_size, [&] { read_image(path, format, bytes, size, *limits, *out); });
}

void module_release(float* pixels) { std::free(pixels); }

int module_write(const char* path, int width, int height, int channels, const float* pixels, char* error,
                 std::size_t error_size) {
  return guarded(error, error_size, [&] { write_image(path, width, height, channels, pixels); });
}

// From OpenImageIO's "extension_list" attribute ("openexr:exr,sxr,mxr;hdr:hdr,rgbe;...").
const char* module_format_for_extension(const char* extension) {
  thread_local std::string found;
  found.clear();
  std::istringstream entries(OIIO::get_string_attribute("extension_list"));
  std::string entry, e;
  while (found.empty() && std::getline(entries, entry, ';')) {
    const std::size_t colon = entry.find(':');
    if (colon == std::string::npos) continue;
    std::istringstream extensions(entry.substr(colon + 1));
    while (std::getline(extensions, e, ','))
      if (e == extension) found = entry.substr(0, colon);
  }
  return found.c_str();
}

const EnvpisOiioApi kApi = {ENVPIS_OIIO_MODULE_ABI, module_read, module_release, module_write,
                            module_format_for_extension};

}  // namespace

extern "C" __attribute__((visibility("default"))) const EnvpisOiioApi* envpis_oiio_module() {
  // Never offer a file to every reader OpenImageIO has (third-party decoders that may take a junk file
  // for a huge image): a file goes to the one reader its content or extension names.
  OIIO::attribute("try_all_readers", 0);
  return &kApi;
}
