// CPU-side images: rendered frames (RGBA8) and read-back fluid buffers (float), PNG files, and the
// comparisons the tests use.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

namespace hapfluid::render {

struct Rgba8Image {
  uint32_t width = 0, height = 0;
  std::vector<uint8_t> rgba;  // row-major, top row first
  const uint8_t* pixel(uint32_t x, uint32_t y) const { return &rgba[(size_t(y) * width + x) * 4]; }
};

struct FloatImage {
  uint32_t width = 0, height = 0;
  std::vector<float> values;  // row-major, top row first
  float at(uint32_t x, uint32_t y) const { return values[size_t(y) * width + x]; }
};

// Both throw std::runtime_error naming the file and the reason.
void write_png(const std::filesystem::path& file, const Rgba8Image& image);
Rgba8Image read_png(const std::filesystem::path& file);

// Peak signal-to-noise ratio over the RGB channels, in dB (infinity for identical images).
double psnr_db(const Rgba8Image& a, const Rgba8Image& b);

// A depth buffer as a grey image for the buffer dumps: near fluid white, far fluid dark, pixels
// whose value is above `no_fluid_above` black.
Rgba8Image depth_to_grey(const FloatImage& depth, float no_fluid_above);

}  // namespace hapfluid::render
