// SPDX-License-Identifier: Apache-2.0
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <sstream>
#include <system_error>

#include "envpis/environment_map.h"
#include "../image_format.h"
#include "png_decode.h"

// EnvironmentMap::load: the envpis::io component, the only part of envpis that needs OpenImageIO.
namespace envpis {

namespace {
constexpr std::size_t kMaxTexels = std::size_t(1) << 28;  // 268M texels, 3.2 GB of RGB floats
// Limits on what a header may claim before any pixel is read. A reader allocates its decoding buffers
// from the header (OpenEXR: up to 256 scanlines of every channel at once), so a 600-byte file claiming
// an 8M-texel-wide image must be refused here, not discovered as a multi-GB allocation. An 8k x 4k RGBA
// float map has 128 KB scanlines: the limits are 128 and 32 times that.
constexpr std::size_t kMaxScanlineBytes = std::size_t(16) << 20;  // one scanline, all channels, in the file
constexpr std::size_t kMaxTileBytes = std::size_t(64) << 20;      // one tile, all channels, in the file
constexpr std::size_t kBandBytes = std::size_t(32) << 20;         // rows decoded at a time (see read_texels)

[[noreturn]] void fail(const std::string& path, const std::string& why) {
  throw Error("cannot load environment map '" + path + "': " + why);
}

std::string first_line(std::string s) {
  const auto nl = s.find('\n');
  if (nl != std::string::npos) s.resize(nl);
  return s.empty() ? std::string("no detail from OpenImageIO") : s;
}


// The reader for the formats environment maps come in, recognized by their first bytes.
std::string format_from_content(const unsigned char* b, std::size_t n) {
  if (n >= 4 && b[0] == 0x76 && b[1] == 0x2f && b[2] == 0x31 && b[3] == 0x01) return "openexr";
  if (n >= 2 && b[0] == '#' && b[1] == '?') return "hdr";  // #?RADIANCE, #?RGBE
  if (n >= 3 && b[0] == 'P' && (b[1] == 'F' || b[1] == 'f') && std::isspace(b[2])) return "pnm";  // PFM
  if (n >= 8 && std::memcmp(b, "\x89PNG\r\n\x1a\n", 8) == 0) return "png";
  if (n >= 4 && (std::memcmp(b, "II*\0", 4) == 0 || std::memcmp(b, "MM\0*", 4) == 0)) return "tiff";
  return {};
}

// OpenImageIO's reader for a file extension (without the dot), from its "extension_list" attribute
// ("openexr:exr,sxr,mxr;hdr:hdr,rgbe;..."); empty when none.
std::string format_from_extension(const std::string& ext) {
  if (ext.empty()) return {};
  std::istringstream entries(OIIO::get_string_attribute("extension_list"));
  std::string entry, e;
  while (std::getline(entries, entry, ';')) {
    const std::size_t colon = entry.find(':');
    if (colon == std::string::npos) continue;
    std::istringstream extensions(entry.substr(colon + 1));
    while (std::getline(extensions, e, ','))
      if (e == ext) return entry.substr(0, colon);
  }
  return {};
}

}  // namespace

namespace {

// Reads channels [0, nc) of every texel of the opened image as float, nc values per texel, row after row.
// The pixels are read in the file's own data format, a band of rows (scanline files) or a row of tiles
// (tiled files) at a time, into a buffer sized here, and converted here. OpenImageIO's read_image() with
// a conversion to float would size its own band buffer from the header (256 rows, or a TIFF's claimed
// rows per strip) and allocate it before finding the data missing: 12 GB for a 600-byte EXR claiming
// 8M x 2 texels.
void read_texels(OIIO::ImageInput& in, const OIIO::ImageSpec& spec, int nc, float* out, const std::string& path) {
  const std::size_t width = static_cast<std::size_t>(spec.width);
  const std::size_t pixel_bytes = spec.pixel_bytes(0, nc, true);  // channels [0, nc), as stored
  const std::size_t row_bytes = width * pixel_bytes;
  int band_rows = spec.tile_width > 0 ? std::min(spec.tile_height, spec.height)
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
    if (!ok) fail(path, "could not read the pixels (corrupt or truncated?): " + first_line(in.geterror()));
    float* dst = out + static_cast<std::size_t>(y) * width * nc;
    const OIIO::stride_t dst_pixel = static_cast<OIIO::stride_t>(nc * sizeof(float));
    std::size_t offset = 0;  // of channel c within a stored pixel
    for (int c = 0; c < nc; ++c) {
      const OIIO::TypeDesc type = spec.channelformat(c);
      if (!OIIO::convert_image(1, spec.width, rows, 1, band.data() + offset, type,
                               static_cast<OIIO::stride_t>(pixel_bytes), static_cast<OIIO::stride_t>(row_bytes),
                               OIIO::AutoStride, dst + c, OIIO::TypeDesc::FLOAT, dst_pixel,
                               dst_pixel * static_cast<OIIO::stride_t>(width), OIIO::AutoStride))
        fail(path, std::string("cannot convert texels stored as ") + type.c_str() + " to float");
      offset += type.size();
    }
  }
}

// Decodes the file with OpenImageIO's reader for `format` alone, header claims bounded first; returns
// interleaved RGB floats (one channel repeated for grey) and the size.
std::vector<float> read_with_oiio(const std::string& path, const std::string& format, int& width, int& height) {
  auto in = OIIO::ImageInput::create(format);
  if (!in) fail(path, "no " + format + " reader in this OpenImageIO: " + first_line(OIIO::geterror()));
  OIIO::ImageSpec opened;
  if (!in->open(path, opened)) {
    const char* name = detail::format_display_name(format);
    fail(path, std::string(name ? name : format.c_str()) + " reader: " + first_line(in->geterror()));
  }
  const OIIO::ImageSpec spec = in->spec();
  if (spec.deep) fail(path, "deep images are not supported");
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
    fail(path, "the image has no pixels");
  if (spec.depth > 1) fail(path, "volume images are not supported");
  const std::size_t texels = static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height);
  if (texels > kMaxTexels) fail(path, "the image is too large (" + std::to_string(spec.width) + "x" +
                                          std::to_string(spec.height) + ")");
  if (spec.scanline_bytes(true) > kMaxScanlineBytes)
    fail(path, "the image's scanlines are implausibly large (" + std::to_string(spec.width) + " texels of " +
                   std::to_string(spec.nchannels) + " channels, " + std::to_string(spec.scanline_bytes(true)) +
                   " bytes each; the limit is " + std::to_string(kMaxScanlineBytes) + ")");
  if (spec.tile_width > 0 && spec.tile_bytes(true) > kMaxTileBytes)
    fail(path, "the image's tiles are implausibly large (" + std::to_string(spec.tile_width) + "x" +
                   std::to_string(spec.tile_height) + " texels of " + std::to_string(spec.nchannels) +
                   " channels)");
  const int nc = std::min(spec.nchannels, 3);  // only the first three channels are used: read no more
  std::vector<float> raw;
  try {
    raw.resize(texels * nc);
    read_texels(*in, spec, nc, raw.data(), path);
  } catch (const std::bad_alloc&) {
    fail(path, "not enough memory for " + std::to_string(spec.width) + "x" + std::to_string(spec.height) + " texels");
  }
  in->close();

  std::vector<float> rgb(texels * 3);
  for (std::size_t i = 0; i < texels; ++i) {
    const float* p = &raw[i * nc];
    rgb[i * 3 + 0] = p[0];
    rgb[i * 3 + 1] = nc >= 3 ? p[1] : p[0];
    rgb[i * 3 + 2] = nc >= 3 ? p[2] : p[0];
  }
  width = spec.width;
  height = spec.height;
  return rgb;
}

}  // namespace

EnvironmentMap EnvironmentMap::load(const std::string& path, const EnvironmentMapOptions& options) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec && ec != std::errc::no_such_file_or_directory) fail(path, ec.message());
  if (!std::filesystem::exists(status)) fail(path, "no such file");
  if (std::filesystem::is_directory(status)) fail(path, "is a directory, not an image file");
  // A FIFO or a device would block or never end: only regular files are read.
  if (!std::filesystem::is_regular_file(status)) fail(path, "is not a regular file");
  if (std::filesystem::file_size(path, ec) == 0 && !ec) fail(path, "the file is empty (0 bytes)");

  unsigned char head[16] = {};
  std::size_t head_bytes = 0;
  {
    errno = 0;
    std::ifstream f(path, std::ios::binary);
    if (!f) fail(path, std::string("cannot open: ") + (errno ? std::strerror(errno) : "unknown reason"));
    f.read(reinterpret_cast<char*>(head), sizeof head);
    head_bytes = static_cast<std::size_t>(f.gcount());
  }

  // The reader: the content's for the usual HDR formats, else the extension's. Never OpenImageIO's
  // fallback that offers a file to every reader it has (third-party decoders that may take a junk
  // file for a huge image).
  std::string ext = detail::lower(std::filesystem::path(path).extension().string());
  if (!ext.empty()) ext.erase(0, 1);
  const std::string by_content = format_from_content(head, head_bytes);
  const std::string by_extension = format_from_extension(ext);
  const std::string format = !by_content.empty() ? by_content : by_extension;
  if (format.empty())
    fail(path, ext.empty() ? "unknown image format (no file extension, and the content is not OpenEXR, "
                             "Radiance HDR, PFM, TIFF or PNG)"
                           : "unknown image format (no reader for the extension '." + ext +
                                 "', and the content is not OpenEXR, Radiance HDR, PFM, TIFF or PNG)");
  int width = 0, height = 0;
  std::vector<float> rgb;
  if (format == "png") {  // libpng directly, never OpenImageIO's PNG reader (png_decode.h says why)
    detail::DecodedPng png;
    try {
      png = detail::decode_png(path, kMaxTexels);
    } catch (const Error& e) {
      fail(path, e.what());
    }
    width = png.width;
    height = png.height;
    rgb = std::move(png.rgb);
  } else {
    rgb = read_with_oiio(path, format, width, height);
  }
  EnvironmentMap map = from_pixels(width, height, std::move(rgb), options);
  map.path_ = path;
  map.report_.format = format;
  map.report_.extension_format = by_extension;
  return map;
}

}  // namespace envpis
