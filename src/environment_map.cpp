#include "envpis/environment_map.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <new>
#include <sstream>
#include <system_error>

#include "envpis/equal_area.h"

namespace envpis {

namespace {
constexpr float kMaxRadiance = 1e30f;
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

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
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

const char* format_display_name(const std::string& format) {
  if (format == "openexr") return "OpenEXR";
  if (format == "hdr") return "Radiance HDR";
  if (format == "pnm") return "PFM";
  if (format == "png") return "PNG";
  if (format == "tiff") return "TIFF";
  return nullptr;
}
}  // namespace

MapLayout parse_map_layout(const std::string& s) {
  if (s == "auto") return MapLayout::Auto;
  if (s == "latlong" || s == "lat-long" || s == "equirect") return MapLayout::LatLong;
  if (s == "equal-area" || s == "equalarea") return MapLayout::EqualArea;
  throw Error("unknown map layout '" + s + "' (expected auto, latlong or equal-area)");
}

const char* to_string(MapLayout layout) {
  switch (layout) {
    case MapLayout::Auto: return "auto";
    case MapLayout::LatLong: return "latlong";
    case MapLayout::EqualArea: return "equal-area";
  }
  return "?";
}

LatLongOrientation parse_latlong_orientation(const std::string& s) {
  if (s == "panorama") return LatLongOrientation::Panorama;
  if (s == "legacy") return LatLongOrientation::Legacy;
  throw Error("unknown lat-long orientation '" + s + "' (expected panorama or legacy)");
}

const char* to_string(LatLongOrientation orientation) {
  return orientation == LatLongOrientation::Legacy ? "legacy" : "panorama";
}

MapFilter parse_map_filter(const std::string& s) {
  if (s == "bilinear") return MapFilter::Bilinear;
  if (s == "nearest") return MapFilter::Nearest;
  throw Error("unknown map filter '" + s + "' (expected bilinear or nearest)");
}

const char* to_string(MapFilter filter) { return filter == MapFilter::Nearest ? "nearest" : "bilinear"; }

Point2 direction_to_latlong(Vec3 d) {
  const float len = length(d);
  const float z = std::clamp(d.z / len, -1.0f, 1.0f);
  float phi = std::atan2(d.y, d.x);
  if (phi < 0) phi += 2 * kPi;
  float u = phi * (0.5f * kInvPi);
  if (u >= 1.0f) u -= 1.0f;
  return {u, std::acos(z) * kInvPi};
}

Vec3 latlong_to_direction(Point2 uv) {
  const float phi = uv.x * 2 * kPi, theta = uv.y * kPi;
  const float s = std::sin(theta);
  return {s * std::cos(phi), s * std::sin(phi), std::cos(theta)};
}

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
  std::string ext = lower(std::filesystem::path(path).extension().string());
  if (!ext.empty()) ext.erase(0, 1);
  const std::string by_content = format_from_content(head, head_bytes);
  const std::string by_extension = format_from_extension(ext);
  const std::string format = !by_content.empty() ? by_content : by_extension;
  if (format.empty())
    fail(path, ext.empty() ? "unknown image format (no file extension, and the content is not OpenEXR, "
                             "Radiance HDR, PFM, TIFF or PNG)"
                           : "unknown image format (no reader for the extension '." + ext +
                                 "', and the content is not OpenEXR, Radiance HDR, PFM, TIFF or PNG)");
  auto in = OIIO::ImageInput::create(format);
  if (!in) fail(path, "no " + format + " reader in this OpenImageIO: " + first_line(OIIO::geterror()));
  OIIO::ImageSpec opened;
  if (!in->open(path, opened)) {
    const char* name = format_display_name(format);
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
  EnvironmentMap map = from_pixels(spec.width, spec.height, std::move(rgb), options);
  map.path_ = path;
  map.report_.format = format;
  map.report_.extension_format = by_extension;
  return map;
}

EnvironmentMap EnvironmentMap::from_pixels(int width, int height, std::vector<float> rgb,
                                           const EnvironmentMapOptions& options) {
  if (width <= 0 || height <= 0) throw Error("environment map size must be positive");
  if (rgb.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3)
    throw Error("environment map pixel array has the wrong size");
  EnvironmentMap map;
  map.width_ = width;
  map.height_ = height;
  map.pixels_ = std::move(rgb);
  map.finish(options);
  return map;
}

void EnvironmentMap::finish(const EnvironmentMapOptions& options) {
  if (!(options.scale >= 0.0f) || !std::isfinite(options.scale))
    throw Error("environment map scale must be finite and >= 0");
  layout_ = options.layout;
  if (layout_ == MapLayout::Auto) layout_ = width_ == height_ ? MapLayout::EqualArea : MapLayout::LatLong;
  if (layout_ == MapLayout::EqualArea && width_ != height_)
    throw Error("an equal-area environment map must be square, got " + std::to_string(width_) + "x" +
                std::to_string(height_));
  scale_ = options.scale;
  orientation_ = options.orientation;
  filter_ = options.filter;
  // to_world = rotation * mirror(x -> -x) for a Panorama lat-long map: the mirror negates the
  // rotation's first column. (See to_world in the header for why the orientation lives here.)
  to_world_ = options.rotation;
  if (layout_ == MapLayout::LatLong && orientation_ == LatLongOrientation::Panorama)
    for (auto& row : to_world_.m) row[0] = -row[0];
  to_map_ = to_world_.transposed();
  max_radiance_ = 0;
  for (float& v : pixels_) {
    if (std::isnan(v)) {
      ++report_.nan_texels;
      v = 0;
    } else if (std::isinf(v)) {
      ++report_.inf_texels;
      v = 0;
    } else if (v < 0) {
      ++report_.negative_texels;
      v = 0;
    }
    v = std::min(v * scale_, kMaxRadiance);  // also catches a huge texel * scale overflowing to inf
    max_radiance_ = std::max(max_radiance_, v);
  }
}

std::vector<std::string> EnvironmentMap::warnings() const {
  std::vector<std::string> w;
  const std::string name = path_.empty() ? std::string("the environment map") : "'" + path_ + "'";
  if (report_.repaired() > 0)
    w.push_back(name + ": " + std::to_string(report_.repaired()) + " texel values were invalid and set to 0 (" +
                std::to_string(report_.nan_texels) + " NaN, " + std::to_string(report_.inf_texels) +
                " infinite, " + std::to_string(report_.negative_texels) + " negative)");
  if (!report_.format.empty() && !report_.extension_format.empty() && report_.format != report_.extension_format) {
    const char* is = format_display_name(report_.format);
    const std::string ext = lower(std::filesystem::path(path_).extension().string());
    w.push_back(name + " contains " + (is ? is : report_.format.c_str()) + " data despite its '" + ext +
                "' extension: read as " + (is ? is : report_.format.c_str()));
  }
  if (layout_ == MapLayout::LatLong && width_ != 2 * height_)
    w.push_back(name + " is read as lat-long but is " + std::to_string(width_) + "x" + std::to_string(height_) +
                ", not 2:1");
  return w;
}

Rgb EnvironmentMap::bilinear_latlong(float u, float v) const {
  const float px = u * width_ - 0.5f, py = v * height_ - 0.5f;
  const float fx = std::floor(px), fy = std::floor(py);
  const float tx = px - fx, ty = py - fy;
  int x0 = static_cast<int>(fx) % width_;
  if (x0 < 0) x0 += width_;
  const int x1 = x0 + 1 == width_ ? 0 : x0 + 1;
  const int y0 = std::clamp(static_cast<int>(fy), 0, height_ - 1);
  const int y1 = std::clamp(static_cast<int>(fy) + 1, 0, height_ - 1);
  return (texel(x0, y0) * (1 - tx) + texel(x1, y0) * tx) * (1 - ty) +
         (texel(x0, y1) * (1 - tx) + texel(x1, y1) * tx) * ty;
}

Rgb EnvironmentMap::bilinear_equal_area(float x, float y) const {
  const int n = width_;
  const float px = x * n - 0.5f, py = y * n - 0.5f;
  const float fx = std::floor(px), fy = std::floor(py);
  const float tx = px - fx, ty = py - fy;
  Rgb acc;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      int xi = static_cast<int>(fx) + i, yi = static_cast<int>(fy) + j;
      if (!equal_area_wrap(n, xi, yi)) {
        xi = std::clamp(xi, 0, n - 1);
        yi = std::clamp(yi, 0, n - 1);
      }
      acc = acc + texel(xi, yi) * ((i ? tx : 1 - tx) * (j ? ty : 1 - ty));
    }
  return acc;
}

// The texel that texture point (x, y) falls in. Outside [0,1) a lat-long map wraps in u and clamps in v;
// an equal-area map wraps across its edges as the sphere does (equal_area_wrap).
Rgb EnvironmentMap::nearest(float x, float y) const {
  const float fx = std::floor(x * width_), fy = std::floor(y * height_);
  // Far outside the image (only for absurd inputs) the float -> int conversion must not overflow.
  int xi = static_cast<int>(std::clamp(fx, -2.0f * width_, 2.0f * width_));
  int yi = static_cast<int>(std::clamp(fy, -2.0f * height_, 2.0f * height_));
  if (layout_ == MapLayout::EqualArea) {
    if (!equal_area_wrap(width_, xi, yi)) {
      xi = std::clamp(xi, 0, width_ - 1);
      yi = std::clamp(yi, 0, height_ - 1);
    }
    return texel(xi, yi);
  }
  xi %= width_;
  if (xi < 0) xi += width_;
  return texel(xi, std::clamp(yi, 0, height_ - 1));
}

Rgb EnvironmentMap::eval_texture(Point2 uv) const {
  if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return {};
  if (filter_ == MapFilter::Nearest) return nearest(uv.x, uv.y);
  return layout_ == MapLayout::EqualArea ? bilinear_equal_area(uv.x, uv.y) : bilinear_latlong(uv.x, uv.y);
}

Rgb EnvironmentMap::eval(Vec3 d) const {
  if (!is_valid_direction(d)) return {};
  const Vec3 m = to_map(d);
  if (layout_ == MapLayout::EqualArea) return eval_texture(equal_area_sphere_to_square(m));
  return eval_texture(direction_to_latlong(m));
}

}  // namespace envpis
