#include "hapfluid/render/image_io.hpp"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <stdexcept>

namespace hapfluid::render {
namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

[[noreturn]] void on_png_error(png_structp png, png_const_charp message) {
  throw std::runtime_error(message);
}

}  // namespace

void write_png(const std::filesystem::path& file, const Rgba8Image& image) {
  if (image.width == 0 || image.height == 0 || image.rgba.size() != size_t(image.width) * image.height * 4)
    throw std::runtime_error(file.string() + ": cannot write an empty or inconsistent image");
  // Written to a temporary name and renamed, so a reader never sees half a PNG.
  const std::filesystem::path partial = file.string() + ".partial";
  {
    File f(std::fopen(partial.c_str(), "wb"));
    if (!f) throw std::runtime_error(file.string() + ": cannot open for writing");
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, on_png_error, nullptr);
    png_infop info = png_create_info_struct(png);
    try {
      png_init_io(png, f.get());
      png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE,
                   PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
      png_set_compression_level(png, 3);  // fast: frames are written at render rate
      png_write_info(png, info);
      for (uint32_t y = 0; y < image.height; ++y)
        png_write_row(png, const_cast<png_bytep>(image.pixel(0, y)));
      png_write_end(png, nullptr);
    } catch (const std::exception& e) {
      png_destroy_write_struct(&png, &info);
      throw std::runtime_error(file.string() + ": PNG write failed: " + e.what());
    }
    png_destroy_write_struct(&png, &info);
    if (std::fflush(f.get()) != 0) throw std::runtime_error(file.string() + ": write failed (disk full?)");
  }
  std::filesystem::rename(partial, file);
}

Rgba8Image read_png(const std::filesystem::path& file) {
  File f(std::fopen(file.c_str(), "rb"));
  if (!f) throw std::runtime_error(file.string() + ": cannot open PNG");
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, on_png_error, nullptr);
  png_infop info = png_create_info_struct(png);
  Rgba8Image image;
  try {
    png_init_io(png, f.get());
    png_read_info(png, info);
    png_set_expand(png);
    png_set_strip_16(png);
    png_set_gray_to_rgb(png);
    png_set_add_alpha(png, 0xff, PNG_FILLER_AFTER);
    png_read_update_info(png, info);
    image.width = png_get_image_width(png, info);
    image.height = png_get_image_height(png, info);
    image.rgba.resize(size_t(image.width) * image.height * 4);
    for (uint32_t y = 0; y < image.height; ++y) png_read_row(png, &image.rgba[size_t(y) * image.width * 4], nullptr);
  } catch (const std::exception& e) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw std::runtime_error(file.string() + ": not a readable PNG: " + e.what());
  }
  png_destroy_read_struct(&png, &info, nullptr);
  return image;
}

double psnr_db(const Rgba8Image& a, const Rgba8Image& b) {
  if (a.width != b.width || a.height != b.height)
    throw std::runtime_error("psnr: images differ in size");
  double sum = 0;
  for (size_t i = 0; i < a.rgba.size(); ++i) {
    if (i % 4 == 3) continue;
    double d = double(a.rgba[i]) - double(b.rgba[i]);
    sum += d * d;
  }
  double mse = sum / (double(a.width) * a.height * 3);
  if (mse == 0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(255.0 * 255.0 / mse);
}

Rgba8Image depth_to_grey(const FloatImage& depth, float no_fluid_above) {
  float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
  for (float v : depth.values)
    if (v <= no_fluid_above && v > 0) lo = std::min(lo, v), hi = std::max(hi, v);
  Rgba8Image out{depth.width, depth.height, std::vector<uint8_t>(depth.values.size() * 4, 255)};
  const float range = hi > lo ? hi - lo : 1.0f;
  for (size_t i = 0; i < depth.values.size(); ++i) {
    float v = depth.values[i];
    uint8_t g = 0;
    if (v <= no_fluid_above && v > 0) g = uint8_t(std::lround(255.0f - 215.0f * (v - lo) / range));
    out.rgba[i * 4] = out.rgba[i * 4 + 1] = out.rgba[i * 4 + 2] = g;
  }
  return out;
}

}  // namespace hapfluid::render
