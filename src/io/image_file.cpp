// SPDX-License-Identifier: Apache-2.0
// Image files: the reader or writer for each file, OpenEXR and PNG directly, the rest through the
// OpenImageIO module.
#include "envpis/image_file.h"

#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <system_error>

#include "../image_format.h"
#include "exr_file.h"
#include "oiio_loader.h"
#include "png_decode.h"
#include "png_encode.h"

namespace envpis {

namespace {

// The reader for the formats images come in, recognized by their first bytes.
std::string format_from_content(const unsigned char* b, std::size_t n) {
  if (n >= 4 && b[0] == 0x76 && b[1] == 0x2f && b[2] == 0x31 && b[3] == 0x01) return "openexr";
  if (n >= 2 && b[0] == '#' && b[1] == '?') return "hdr";  // #?RADIANCE, #?RGBE
  if (n >= 3 && b[0] == 'P' && (b[1] == 'F' || b[1] == 'f') && std::isspace(b[2])) return "pnm";  // PFM
  if (n >= 8 && std::memcmp(b, "\x89PNG\r\n\x1a\n", 8) == 0) return "png";
  if (n >= 4 && (std::memcmp(b, "II*\0", 4) == 0 || std::memcmp(b, "MM\0*", 4) == 0)) return "tiff";
  if (n >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return "jpeg";
  return {};
}

// OpenImageIO 2.4's readers for the usual extensions (its "extension_list"), known without loading it.
std::string known_format(const std::string& ext) {
  static const char* const kTable[][2] = {
      {"exr", "openexr"}, {"sxr", "openexr"}, {"mxr", "openexr"}, {"hdr", "hdr"},   {"rgbe", "hdr"},
      {"png", "png"},     {"ppm", "pnm"},     {"pgm", "pnm"},     {"pbm", "pnm"},   {"pnm", "pnm"},
      {"pfm", "pnm"},     {"tif", "tiff"},    {"tiff", "tiff"},   {"tx", "tiff"},   {"env", "tiff"},
      {"sm", "tiff"},     {"vsm", "tiff"},    {"jpg", "jpeg"},    {"jpe", "jpeg"},  {"jpeg", "jpeg"},
      {"jif", "jpeg"},    {"jfif", "jpeg"},   {"jfi", "jpeg"}};
  for (const auto& row : kTable)
    if (ext == row[0]) return row[1];
  return {};
}

ImageFile from_module(const char* path, const std::string& format, const std::uint8_t* bytes, std::size_t size,
                      const ImageReadLimits& limits) {
  const EnvpisOiioApi& api = detail::oiio_module();
  const EnvpisOiioLimits l{limits.max_channels, limits.max_texels, limits.max_side};
  EnvpisOiioImage img{};
  char error[512] = {};
  if (api.read(path, format.c_str(), bytes, size, &l, &img, error, sizeof error) != 0) throw Error(error);
  ImageFile out;
  out.width = img.width;
  out.height = img.height;
  out.channels = img.channels;
  out.integer_coded = img.integer_coded != 0;
  out.format = format;
  try {
    out.pixels.assign(img.pixels, img.pixels + std::size_t(img.width) * img.height * img.channels);
  } catch (const std::bad_alloc&) {
    api.release(img.pixels);
    throw Error("not enough memory for " + std::to_string(img.width) + "x" + std::to_string(img.height) + " texels");
  }
  api.release(img.pixels);
  return out;
}

std::string extension_of(const std::string& path) {
  std::string ext = detail::lower(std::filesystem::path(path).extension().string());
  if (!ext.empty()) ext.erase(0, 1);
  return ext;
}

}  // namespace

std::string image_format_for_extension(const std::string& extension) {
  const std::string ext = detail::lower(extension);
  if (ext.empty()) return {};
  if (std::string f = known_format(ext); !f.empty()) return f;
  return detail::oiio_module().format_for_extension(ext.c_str());
}

ImageFile read_image_file(const std::string& path, const ImageReadLimits& limits) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec && ec != std::errc::no_such_file_or_directory) throw Error(ec.message());
  if (!std::filesystem::exists(status)) throw Error("no such file");
  if (std::filesystem::is_directory(status)) throw Error("is a directory, not an image file");
  // A FIFO or a device would block or never end: only regular files are read.
  if (!std::filesystem::is_regular_file(status)) throw Error("is not a regular file");
  if (std::filesystem::file_size(path, ec) == 0 && !ec) throw Error("the file is empty (0 bytes)");

  unsigned char head[16] = {};
  std::size_t head_bytes = 0;
  {
    errno = 0;
    std::ifstream f(path, std::ios::binary);
    if (!f) throw Error(std::string("cannot open: ") + (errno ? std::strerror(errno) : "unknown reason"));
    f.read(reinterpret_cast<char*>(head), sizeof head);
    head_bytes = static_cast<std::size_t>(f.gcount());
  }
  // The content's reader for the usual formats, else the extension's.
  const std::string ext = extension_of(path);
  std::string format = format_from_content(head, head_bytes);
  if (format.empty()) format = image_format_for_extension(ext);
  if (format.empty())
    throw Error(ext.empty() ? "unknown image format (no file extension, and the content is not OpenEXR, "
                              "Radiance HDR, PFM, TIFF, PNG or JPEG)"
                            : "unknown image format (no reader for the extension '." + ext +
                                  "', and the content is not OpenEXR, Radiance HDR, PFM, TIFF, PNG or JPEG)");
  if (format == "openexr") return detail::read_exr(path, limits);
  if (format == "png") return detail::decode_png(path, limits);
  return from_module(path.c_str(), format, nullptr, 0, limits);
}

ImageFile decode_image(const std::uint8_t* bytes, std::size_t size, const ImageReadLimits& limits) {
  const std::string format = format_from_content(bytes, size);
  if (format == "png") return detail::decode_png(bytes, size, limits);
  if (format == "jpeg") return from_module("embedded.jpg", format, bytes, size, limits);
  throw Error("the image data is neither PNG nor JPEG");
}

void write_image_file(const std::string& path, int width, int height, int channels, const float* pixels,
                      const std::vector<std::string>& channel_names, const std::vector<ImageAttribute>& attributes) {
  const std::string ext = extension_of(path);
  if (ext == "exr") return detail::write_exr(path, width, height, channels, pixels, channel_names, attributes);
  if (ext == "png") return detail::encode_png(path, width, height, channels, pixels);
  const EnvpisOiioApi* api = nullptr;
  try {
    api = &detail::oiio_module();
  } catch (const Error& e) {
    throw Error("cannot write '" + path + "': " + e.what());
  }
  char error[512] = {};
  if (api->write(path.c_str(), width, height, channels, pixels, error, sizeof error) != 0)
    throw Error("cannot write '" + path + "': " + error);
}

}  // namespace envpis
