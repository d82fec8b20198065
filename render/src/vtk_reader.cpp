#include "hapfluid/render/vtk_reader.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace hapfluid::render {
namespace {

std::vector<std::string> split(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> tokens;
  for (std::string t; in >> t;) tokens.push_back(t);
  return tokens;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

class Parser {
 public:
  Parser(const std::string& bytes, std::string name) : data_(bytes), name_(std::move(name)) {}

  VtkPoints parse() {
    expect_prefix(line(), "# vtk DataFile Version", "the first line must be \"# vtk DataFile Version x.x\"");
    const std::string title = line();
    const std::string encoding = lower(trimmed(line()));
    if (encoding == "binary") binary_ = true;
    else if (encoding != "ascii") fail("the third line must be ASCII or BINARY, not \"" + encoding + "\"");
    auto dataset = split(next_header());
    if (dataset.size() != 2 || lower(dataset[0]) != "dataset")
      fail("expected \"DATASET POLYDATA\" or \"DATASET UNSTRUCTURED_GRID\"");
    const std::string kind = lower(dataset[1]);
    if (kind != "polydata" && kind != "unstructured_grid")
      fail("DATASET " + dataset[1] + " is not supported (POLYDATA or UNSTRUCTURED_GRID)");

    VtkPoints out;
    out.title = trimmed(title);
    bool have_points = false;
    size_t section_count = 0;
    bool in_point_data = false;
    while (true) {
      std::string header = next_header();
      if (header.empty()) break;
      auto t = split(header);
      const std::string key = lower(t[0]);
      if (key == "points") {
        need(t, 3, "POINTS <count> <type>");
        const size_t n = count(t[1]);
        auto values = read_values(3 * n, t[2]);
        out.points_m.resize(n);
        for (size_t i = 0; i < n; ++i) out.points_m[i] = {values[3 * i], values[3 * i + 1], values[3 * i + 2]};
        have_points = true;
      } else if (key == "vertices" || key == "lines" || key == "polygons" || key == "triangle_strips" ||
                 key == "cells") {
        need(t, 3, key + " <count> <size>");
        skip_cells(count(t[1]), count(t[2]));
      } else if (key == "cell_types") {
        need(t, 2, "CELL_TYPES <count>");
        read_values(count(t[1]), "int");
      } else if (key == "point_data" || key == "cell_data") {
        need(t, 2, key + " <count>");
        section_count = count(t[1]);
        in_point_data = key == "point_data";
        if (in_point_data && have_points && section_count != out.points_m.size())
          fail("POINT_DATA " + t[1] + " does not match POINTS " + std::to_string(out.points_m.size()));
      } else if (key == "scalars") {
        if (t.size() < 3) fail("expected SCALARS <name> <type> [components]");
        const size_t components = t.size() > 3 ? count(t[3]) : 1;
        auto table = split(next_header());
        if (table.empty() || lower(table[0]) != "lookup_table") fail("SCALARS must be followed by LOOKUP_TABLE");
        auto values = read_values(section_count * components, t[2]);
        if (in_point_data && components == 1) out.point_scalars[t[1]] = std::move(values);
      } else if (key == "vectors" || key == "normals") {
        need(t, 3, key + " <name> <type>");
        read_values(section_count * 3, t[2]);
      } else if (key == "field") {
        need(t, 3, "FIELD <name> <arrays>");
        read_field(count(t[2]), in_point_data, section_count, out);
      } else if (key == "metadata") {
        skip_metadata();
      } else {
        fail("unsupported section \"" + t[0] + "\"");
      }
    }
    if (!have_points) fail("no POINTS section");
    for (const auto& [name, values] : out.point_scalars)
      if (values.size() != out.points_m.size())
        fail("point array \"" + name + "\" has " + std::to_string(values.size()) + " values for " +
             std::to_string(out.points_m.size()) + " points");
    return out;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(name_ + ": line " + std::to_string(line_number_) + ": " + what);
  }

  // Whitespace as split() sees it: a line of only \v or \f is blank, not a header without a word.
  static std::string trimmed(const std::string& s) {
    size_t a = s.find_first_not_of(" \t\r\n\v\f"), b = s.find_last_not_of(" \t\r\n\v\f");
    return a == std::string::npos ? "" : s.substr(a, b - a + 1);
  }

  std::string line() {
    if (pos_ >= data_.size()) fail("unexpected end of file");
    size_t end = data_.find('\n', pos_);
    if (end == std::string::npos) end = data_.size();
    std::string s = data_.substr(pos_, end - pos_);
    pos_ = std::min(end + 1, data_.size());
    ++line_number_;
    if (!s.empty() && s.back() == '\r') s.pop_back();
    return s;
  }

  // The next non-blank line, or "" at the end of the file.
  std::string next_header() {
    while (pos_ < data_.size()) {
      std::string s = trimmed(line());
      if (!s.empty()) return s;
    }
    return "";
  }

  void expect_prefix(const std::string& s, const char* prefix, const char* message) {
    if (s.rfind(prefix, 0) != 0) fail(message);
  }

  void need(const std::vector<std::string>& t, size_t n, const std::string& form) {
    if (t.size() < n) fail("expected " + form);
  }

  size_t count(const std::string& s) {
    char* end = nullptr;
    long long v = std::strtoll(s.c_str(), &end, 10);
    if (end == s.c_str() || *end || v < 0 || v > (1ll << 31)) fail("\"" + s + "\" is not a valid count");
    return size_t(v);
  }

  static size_t type_size(const std::string& type) {
    const std::string t = lower(type);
    if (t == "float") return 4;
    if (t == "double" || t == "long" || t == "unsigned_long" || t == "vtktypeint64" || t == "vtktypeuint64") return 8;
    if (t == "int" || t == "unsigned_int" || t == "vtkidtype" || t == "vtktypeint32" || t == "vtktypeuint32") return 4;
    if (t == "short" || t == "unsigned_short") return 2;
    if (t == "char" || t == "unsigned_char" || t == "bit") return 1;
    return 0;
  }

  std::vector<double> read_values(size_t n, const std::string& type) {
    const size_t size = type_size(type);
    if (size == 0) fail("unsupported data type \"" + type + "\"");
    // The count comes from the file: check that the rest of the file can hold that many values
    // before allocating them. A binary value takes `size` bytes, an ASCII one at least a
    // character and a separator.
    const size_t left = data_.size() - pos_;
    if (binary_ ? n > left / size : n > (left + 1) / 2)
      fail(std::string(binary_ ? "binary" : "ASCII") + " data ends early: " + std::to_string(n) + " values of " +
           type + " do not fit in the file");
    std::vector<double> out(n);
    if (!binary_) {
      for (size_t i = 0; i < n; ++i) out[i] = ascii_number();
      return out;
    }
    const std::string t = lower(type);
    for (size_t i = 0; i < n; ++i) {
      unsigned char b[8];
      std::memcpy(b, data_.data() + pos_ + i * size, size);
      std::reverse(b, b + size);  // legacy VTK binary is big-endian
      if (t == "float") out[i] = as<float>(b);
      else if (t == "double") out[i] = as<double>(b);
      else if (t == "long" || t == "vtktypeint64") out[i] = double(as<int64_t>(b));
      else if (t == "unsigned_long" || t == "vtktypeuint64") out[i] = double(as<uint64_t>(b));
      else if (t == "int" || t == "vtkidtype" || t == "vtktypeint32") out[i] = as<int32_t>(b);
      else if (t == "unsigned_int" || t == "vtktypeuint32") out[i] = as<uint32_t>(b);
      else if (t == "short") out[i] = as<int16_t>(b);
      else if (t == "unsigned_short") out[i] = as<uint16_t>(b);
      else if (t == "char") out[i] = as<int8_t>(b);
      else out[i] = as<uint8_t>(b);
    }
    pos_ += n * size;
    return out;
  }

  template <typename T>
  static T as(const unsigned char* little_endian) {
    static_assert(std::endian::native == std::endian::little, "this reader assumes a little-endian host");
    T v;
    std::memcpy(&v, little_endian, sizeof v);
    return v;
  }

  double ascii_number() {
    while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) {
      if (data_[pos_] == '\n') ++line_number_;
      ++pos_;
    }
    if (pos_ >= data_.size()) fail("file ends in the middle of a data section");
    const char* start = data_.c_str() + pos_;
    char* end = nullptr;
    double v = std::strtod(start, &end);
    if (end == start) fail("expected a number, found \"" + data_.substr(pos_, 12) + "\"");
    pos_ += size_t(end - start);
    return v;
  }

  // Legacy cells: <size> integers. VTK 5.x: OFFSETS and CONNECTIVITY arrays with their own types.
  void skip_cells(size_t cells, size_t size) {
    const size_t saved_pos = pos_, saved_line = line_number_;
    auto t = split(next_header());
    if (!t.empty() && lower(t[0]) == "offsets") {
      need(t, 2, "OFFSETS <type>");
      read_values(cells, t[1]);
      auto c = split(next_header());
      if (c.size() < 2 || lower(c[0]) != "connectivity") fail("OFFSETS must be followed by CONNECTIVITY <type>");
      read_values(size, c[1]);
      return;
    }
    pos_ = saved_pos;
    line_number_ = saved_line;
    read_values(size, "int");
  }

  void read_field(size_t arrays, bool point_data, size_t section_count, VtkPoints& out) {
    for (size_t a = 0; a < arrays; ++a) {
      auto t = split(next_header());
      if (!t.empty() && lower(t[0]) == "metadata") {
        skip_metadata();
        t = split(next_header());
      }
      if (t.size() < 4) fail("expected a field array \"<name> <components> <tuples> <type>\"");
      const size_t components = count(t[1]), tuples = count(t[2]);
      auto values = read_values(components * tuples, t[3]);
      if (t[0] == "TIME" && values.size() == 1) out.time_s = values[0];
      else if (point_data && components == 1 && tuples == section_count) out.point_scalars[t[0]] = std::move(values);
    }
  }

  void skip_metadata() {
    while (pos_ < data_.size() && !trimmed(line()).empty()) {
    }
  }

  const std::string& data_;
  std::string name_;
  size_t pos_ = 0;
  size_t line_number_ = 0;
  bool binary_ = false;
};

}  // namespace

VtkPoints parse_vtk_points(const std::string& bytes, const std::string& name) { return Parser(bytes, name).parse(); }

VtkPoints read_vtk_points(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(file.string() + ": cannot open VTK file");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_vtk_points(bytes, file.string());
}

}  // namespace hapfluid::render
