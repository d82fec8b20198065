#include "hapfluid/config/json_output.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <system_error>

#include "hapfluid/config/build_id.hpp"

namespace hapfluid::config {

std::string json_text(const Json& value) {
  return value.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string json_line(const Json& value) {
  return value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

Json bench_record(const std::string& bench, Json params, Json metrics) {
  Json r;
  r["bench"] = bench;
  r["build_id"] = build_id();
  r["params"] = std::move(params);
  r["metrics"] = std::move(metrics);
  return r;
}

void write_json_atomically(const std::filesystem::path& file, const Json& value) {
  const std::string text = json_text(value);
  std::filesystem::path part = file;
  part += ".part";
  {
    std::ofstream out(part, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + part.string() + ": " + std::strerror(errno));
    out << text;
    out.close();
    if (!out) throw std::runtime_error("cannot write " + part.string() + ": " + std::strerror(errno));
  }
  std::error_code ec;
  std::filesystem::rename(part, file, ec);
  if (ec) throw std::runtime_error("cannot rename " + part.string() + " to " + file.string() + ": " + ec.message());
}

}  // namespace hapfluid::config
