#include "hapfluid/render/bodies_csv.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace hapfluid::render {
namespace {

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) {
    while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
    while (!cell.empty() && cell.front() == ' ') cell.erase(cell.begin());
    cells.push_back(cell);
  }
  return cells;
}

}  // namespace

BodyHistory BodyHistory::load(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot open the body history");
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(file.string() + ": empty file (expected a header line)");
  const auto header = split_csv(line);
  const char* needed[] = {"t", "body", "px", "py", "pz", "qw", "qx", "qy", "qz"};
  size_t column[9];
  for (int i = 0; i < 9; ++i) {
    auto it = std::find(header.begin(), header.end(), needed[i]);
    if (it == header.end())
      throw std::runtime_error(file.string() + ": line 1: missing column \"" + needed[i] +
                               "\" (expected t,body,px,py,pz,qw,qx,qy,qz,...)");
    column[i] = size_t(it - header.begin());
  }
  BodyHistory history;
  size_t line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty() || line == "\r") continue;
    const auto cells = split_csv(line);
    auto number = [&](int i) {
      const size_t c = column[i];
      if (c >= cells.size())
        throw std::runtime_error(file.string() + ": line " + std::to_string(line_number) + ": missing " + needed[i]);
      char* end = nullptr;
      double v = std::strtod(cells[c].c_str(), &end);
      if (end == cells[c].c_str() || *end)
        throw std::runtime_error(file.string() + ": line " + std::to_string(line_number) + ": " + needed[i] + " = \"" +
                                 cells[c] + "\" is not a number");
      return v;
    };
    BodySample s;
    s.t_s = number(0);
    if (column[1] >= cells.size())
      throw std::runtime_error(file.string() + ": line " + std::to_string(line_number) + ": missing body");
    s.pose.position_m = glm::vec3(number(2), number(3), number(4));
    glm::quat q(float(number(5)), float(number(6)), float(number(7)), float(number(8)));
    const float len = glm::length(q);
    if (!(len > 1e-6f))
      throw std::runtime_error(file.string() + ": line " + std::to_string(line_number) + ": zero orientation quaternion");
    s.pose.orientation = q / len;
    history.samples_[cells[column[1]]].push_back(s);
  }
  for (auto& [name, samples] : history.samples_)
    std::stable_sort(samples.begin(), samples.end(), [](const BodySample& a, const BodySample& b) { return a.t_s < b.t_s; });
  return history;
}

bool BodyHistory::pose_at(const std::string& body, double t, BodyPose& pose) const {
  auto it = samples_.find(body);
  if (it == samples_.end() || it->second.empty()) return false;
  const auto& s = it->second;
  auto after = std::lower_bound(s.begin(), s.end(), t, [](const BodySample& a, double v) { return a.t_s < v; });
  if (after == s.begin()) return pose = s.front().pose, true;
  if (after == s.end()) return pose = s.back().pose, true;
  const BodySample& a = *(after - 1);
  const BodySample& b = *after;
  const float u = b.t_s > a.t_s ? float((t - a.t_s) / (b.t_s - a.t_s)) : 1.0f;
  pose.position_m = glm::mix(a.pose.position_m, b.pose.position_m, u);
  pose.orientation = glm::slerp(a.pose.orientation, b.pose.orientation, u);
  return true;
}

std::vector<std::string> BodyHistory::bodies() const {
  std::vector<std::string> names;
  for (const auto& [name, samples] : samples_) names.push_back(name);
  return names;
}

}  // namespace hapfluid::render
