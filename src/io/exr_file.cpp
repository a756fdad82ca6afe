// SPDX-License-Identifier: Apache-2.0
#include "exr_file.h"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfTileDescriptionAttribute.h>

#include <algorithm>
#include <exception>
#include <mutex>
#include <new>

namespace envpis::detail {

namespace {

// Header claims bounded before any pixel is read (see oiio_module.cpp for the same limits and why).
// OpenEXR sizes its decoding buffers from the header when the file is opened; its own sanity check
// refuses sides beyond kMaxSide there, before those buffers exist.
constexpr int kMaxSide = 1 << 16;
constexpr std::size_t kMaxScanlineBytes = std::size_t(16) << 20;
constexpr std::size_t kMaxTileBytes = std::size_t(64) << 20;

std::string first_line(std::string s) {
  const auto nl = s.find('\n');
  if (nl != std::string::npos) s.resize(nl);
  return s.empty() ? std::string("no detail from OpenEXR") : s;
}

void bound_header_sizes() {
  static std::once_flag once;
  std::call_once(once, [] {
    Imf::Header::setMaxImageSize(kMaxSide, kMaxSide);
    Imf::Header::setMaxTileSize(kMaxSide, kMaxSide);
  });
}

std::size_t type_bytes(Imf::PixelType t) { return t == Imf::HALF ? 2 : 4; }

// R, G, B (or Y when none of them is there), then A (those present), then the others in the file's
// (alphabetical) order.
std::vector<std::string> channel_order(const Imf::ChannelList& list) {
  std::vector<std::string> names;
  for (const char* c : {"R", "G", "B"})
    if (list.findChannel(c)) names.emplace_back(c);
  if (names.empty() && list.findChannel("Y")) names.emplace_back("Y");
  if (list.findChannel("A")) names.emplace_back("A");
  for (auto it = list.begin(); it != list.end(); ++it)
    if (std::find(names.begin(), names.end(), it.name()) == names.end()) names.emplace_back(it.name());
  return names;
}

void check_header(const Imf::Header& header, const ImageReadLimits& limits) {
  const Imath::Box2i dw = header.dataWindow();
  const long long w = static_cast<long long>(dw.max.x) - dw.min.x + 1;
  const long long h = static_cast<long long>(dw.max.y) - dw.min.y + 1;
  if (w <= 0 || h <= 0 || header.channels().begin() == header.channels().end())
    throw Error("the image has no pixels");
  if (static_cast<unsigned long long>(w * h) > limits.max_texels ||
      (limits.max_side > 0 && std::max(w, h) > limits.max_side))
    throw Error("the image is too large (" + std::to_string(w) + "x" + std::to_string(h) + ")");
  std::size_t pixel_bytes = 0;
  int channels = 0;
  for (auto it = header.channels().begin(); it != header.channels().end(); ++it, ++channels) {
    if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
      throw Error("subsampled channels are not supported");
    pixel_bytes += type_bytes(it.channel().type);
  }
  if (std::size_t(w) * pixel_bytes > kMaxScanlineBytes)
    throw Error("the image's scanlines are implausibly large (" + std::to_string(w) + " texels of " +
                std::to_string(channels) + " channels, " + std::to_string(std::size_t(w) * pixel_bytes) +
                " bytes each; the limit is " + std::to_string(kMaxScanlineBytes) + ")");
  if (header.hasTileDescription()) {
    const Imf::TileDescription& t = header.tileDescription();
    if (std::size_t(t.xSize) * t.ySize * pixel_bytes > kMaxTileBytes)
      throw Error("the image's tiles are implausibly large (" + std::to_string(t.xSize) + "x" +
                  std::to_string(t.ySize) + " texels of " + std::to_string(channels) + " channels)");
  }
}

ImageFile decode(const std::string& path, const ImageReadLimits& limits) {
  Imf::InputFile file(path.c_str());
  const Imf::Header& header = file.header();
  if (header.hasType() && Imf::isDeepData(header.type()))
    throw Error("deep images are not supported");
  check_header(header, limits);
  const std::vector<std::string> names = channel_order(header.channels());
  const Imath::Box2i dw = header.dataWindow();
  ImageFile img;
  img.width = dw.max.x - dw.min.x + 1;
  img.height = dw.max.y - dw.min.y + 1;
  img.channels = std::min<int>(static_cast<int>(names.size()), std::max(1, limits.max_channels));
  img.format = "openexr";
  img.pixels.resize(std::size_t(img.width) * std::size_t(img.height) * std::size_t(img.channels));
  const std::size_t x_stride = sizeof(float) * img.channels;
  const std::size_t y_stride = x_stride * img.width;
  Imf::FrameBuffer fb;
  for (int c = 0; c < img.channels; ++c)
    fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, img.pixels.data() + c, dw, x_stride, y_stride));
  file.setFrameBuffer(fb);
  try {
    file.readPixels(dw.min.y, dw.max.y);
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    throw Error("could not read the pixels (corrupt or truncated?): OpenEXR reader: " + first_line(e.what()));
  }
  return img;
}

}  // namespace

ImageFile read_exr(const std::string& path, const ImageReadLimits& limits) {
  bound_header_sizes();
  try {
    return decode(path, limits);
  } catch (const Error&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw Error("not enough memory to decode the image");
  } catch (const std::exception& e) {
    throw Error("OpenEXR reader: " + first_line(e.what()));
  }
}

void write_exr(const std::string& path, int width, int height, int channels, const float* pixels,
               const std::vector<std::string>& channel_names, const std::vector<ImageAttribute>& attributes) {
  // Grey is Y (with A), colour R, G, B (with A), as OpenEXR's own RGBA interface names them.
  static const char* const kDefault[4][4] = {{"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
  if (width < 1 || height < 1 || channels < 1 || (channel_names.empty() && channels > 4) ||
      (!channel_names.empty() && int(channel_names.size()) != channels))
    throw Error("cannot write '" + path + "': " + std::to_string(channels) + " channels of " +
                std::to_string(width) + "x" + std::to_string(height) + " pixels, " +
                std::to_string(channel_names.size()) + " channel names");
  try {
    Imf::Header header(width, height);
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const ImageAttribute& a : attributes) {
      if (const int* i = std::get_if<int>(&a.value)) header.insert(a.name, Imf::IntAttribute(*i));
      else header.insert(a.name, Imf::StringAttribute(std::get<std::string>(a.value)));
    }
    std::vector<std::string> names(channels);
    for (int c = 0; c < channels; ++c) names[c] = channel_names.empty() ? kDefault[channels - 1][c] : channel_names[c];
    for (const std::string& n : names) header.channels().insert(n, Imf::Channel(Imf::FLOAT));
    Imf::OutputFile file(path.c_str(), header);
    Imf::FrameBuffer fb;
    const std::size_t x_stride = sizeof(float) * channels;
    for (int c = 0; c < channels; ++c)  // OpenEXR writes through a const-less pointer but only reads it
      fb.insert(names[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(pixels + c)), x_stride,
                                     x_stride * width));
    file.setFrameBuffer(fb);
    file.writePixels(height);
  } catch (const std::exception& e) {
    throw Error("cannot write '" + path + "': " + first_line(e.what()));
  }
}

}  // namespace envpis::detail
