#include "toml_reader.hpp"

#include <charconv>
#include <cmath>
#include <sstream>

namespace hapfluid::config::detail {

// The value as a user would write it: shortest round-trip numbers, double-quoted strings.
static void write_value(std::string& out, const toml::node& node) {
  if (const auto* f = node.as_floating_point()) {
    char buf[64];
    auto result = std::to_chars(buf, buf + sizeof buf, f->get());
    std::string text(buf, result.ptr);
    if (std::isfinite(f->get()) && text.find_first_of(".e") == std::string::npos) text += ".0";
    out += text;
  } else if (const auto* i = node.as_integer()) {
    out += std::to_string(i->get());
  } else if (const auto* b = node.as_boolean()) {
    out += b->get() ? "true" : "false";
  } else if (const auto* str = node.as_string()) {
    out += '"' + str->get() + '"';
  } else if (const auto* a = node.as_array()) {
    out += '[';
    for (size_t k = 0; k < a->size(); ++k) {
      if (k) out += ", ";
      write_value(out, *a->get(k));
    }
    out += ']';
  } else if (node.is_table()) {
    out += "{...}";
  } else {
    std::ostringstream other;
    node.visit([&](const auto& value) { other << value; });
    out += other.str();
  }
}

std::string describe(const toml::node& node) {
  std::string text;
  write_value(text, node);
  if (text.size() > 80) text = text.substr(0, 77) + "...";
  return text;
}

int line_of(const toml::node& node) { return static_cast<int>(node.source().begin.line); }

Reader::Reader(const toml::table& table, std::string path, Diagnostics& diag)
    : table_(&table), path_(std::move(path)), diag_(&diag) {}

std::string Reader::key_path(std::string_view key) const {
  if (path_.empty()) return std::string(key);
  return path_ + "." + std::string(key);
}

const toml::node* Reader::get(std::string_view key) {
  known_.insert(std::string(key));
  return table_->get(key);
}

void Reader::wrong_type(std::string_view key, const toml::node& node, const std::string& expected) {
  diag_->add(line_of(node), key_path(key), describe(node), "must be " + expected);
}

void Reader::check(std::string_view key, bool ok, const std::string& reason) {
  if (ok) return;
  const toml::node* node = table_->get(key);
  diag_->add(node ? line_of(*node) : line(), key_path(key), node ? describe(*node) : "", reason);
}

void Reader::problem(std::string_view key, const std::string& reason) {
  const toml::node* node = table_->get(key);
  diag_->add(node ? line_of(*node) : line(), key_path(key), node ? describe(*node) : "", reason);
}

static std::optional<double> as_double(const toml::node& node) {
  if (const auto* f = node.as_floating_point()) return f->get();
  if (const auto* i = node.as_integer()) return static_cast<double>(i->get());
  return std::nullopt;
}

double Reader::number(std::string_view key, double fallback) {
  return optional_number(key).value_or(fallback);
}

std::optional<double> Reader::optional_number(std::string_view key) {
  const toml::node* node = get(key);
  if (!node) return std::nullopt;
  auto value = as_double(*node);
  if (!value) {
    wrong_type(key, *node, "a number");
    return std::nullopt;
  }
  if (!std::isfinite(*value)) {
    wrong_type(key, *node, "finite");
    return std::nullopt;
  }
  return value;
}

double Reader::required_number(std::string_view key) {
  if (!table_->contains(key)) {
    known_.insert(std::string(key));
    diag_->add(line(), key_path(key), "", "missing (a number is required)");
    return 0.0;
  }
  return optional_number(key).value_or(0.0);
}

long long Reader::integer(std::string_view key, long long fallback) {
  const toml::node* node = get(key);
  if (!node) return fallback;
  if (const auto* i = node->as_integer()) return i->get();
  wrong_type(key, *node, "an integer");
  return fallback;
}

bool Reader::boolean(std::string_view key, bool fallback) {
  const toml::node* node = get(key);
  if (!node) return fallback;
  if (const auto* b = node->as_boolean()) return b->get();
  wrong_type(key, *node, "true or false");
  return fallback;
}

std::string Reader::string(std::string_view key, std::string fallback) {
  const toml::node* node = get(key);
  if (!node) return fallback;
  if (const auto* s = node->as_string()) return s->get();
  wrong_type(key, *node, "a string");
  return fallback;
}

std::optional<std::string> Reader::required_string(std::string_view key) {
  const toml::node* node = get(key);
  if (!node) {
    diag_->add(line(), key_path(key), "", "missing (a string is required)");
    return std::nullopt;
  }
  if (const auto* s = node->as_string()) return s->get();
  wrong_type(key, *node, "a string");
  return std::nullopt;
}

static std::optional<std::vector<double>> numbers(const toml::node& node, size_t count) {
  const auto* array = node.as_array();
  if (!array || array->size() != count) return std::nullopt;
  std::vector<double> values;
  for (const auto& element : *array) {
    auto v = as_double(element);
    if (!v || !std::isfinite(*v)) return std::nullopt;
    values.push_back(*v);
  }
  return values;
}

Vec3 Reader::vec3(std::string_view key, Vec3 fallback) {
  if (!table_->contains(key)) {
    known_.insert(std::string(key));
    return fallback;
  }
  return required_vec3(key).value_or(fallback);
}

void Reader::positive(std::string_view key, double& value) {
  value = number(key, value);
  check(key, value > 0, "must be > 0");
}

std::optional<Vec3> Reader::required_vec3(std::string_view key) {
  if (!table_->contains(key)) {
    known_.insert(std::string(key));
    diag_->add(line(), key_path(key), "", "missing (an array of 3 numbers is required)");
    return std::nullopt;
  }
  const toml::node* node = get(key);
  auto v = numbers(*node, 3);
  if (!v) {
    wrong_type(key, *node, "an array of 3 finite numbers");
    return std::nullopt;
  }
  return Vec3{(*v)[0], (*v)[1], (*v)[2]};
}

Quat Reader::quaternion(std::string_view key, Quat fallback) {
  const toml::node* node = get(key);
  if (!node) return fallback;
  auto v = numbers(*node, 4);
  if (!v) {
    wrong_type(key, *node, "an array of 4 finite numbers [w, x, y, z]");
    return fallback;
  }
  double norm = std::sqrt((*v)[0] * (*v)[0] + (*v)[1] * (*v)[1] + (*v)[2] * (*v)[2] + (*v)[3] * (*v)[3]);
  if (norm < 1e-9) {
    diag_->add(line_of(*node), key_path(key), describe(*node), "must be a non-zero quaternion [w, x, y, z]");
    return fallback;
  }
  return Quat{(*v)[0] / norm, (*v)[1] / norm, (*v)[2] / norm, (*v)[3] / norm};
}

std::optional<Reader> Reader::table(std::string_view key) {
  const toml::node* node = get(key);
  if (!node) return std::nullopt;
  if (const auto* t = node->as_table()) return Reader(*t, key_path(key), *diag_);
  wrong_type(key, *node, "a table");
  return std::nullopt;
}

std::vector<Reader> Reader::tables(std::string_view key) {
  std::vector<Reader> out;
  const toml::node* node = get(key);
  if (!node) return out;
  const auto* array = node->as_array();
  if (!array) {
    wrong_type(key, *node, "an array of tables ([[" + std::string(key) + "]])");
    return out;
  }
  size_t index = 0;
  for (const auto& element : *array) {
    const auto* t = element.as_table();
    if (!t) {
      diag_->add(line_of(element), key_path(key) + "[" + std::to_string(index) + "]", describe(element),
                 "must be a table");
    } else {
      std::string element_path = key_path(key);
      const auto* name = t->get_as<std::string>("name");
      element_path += name ? "." + name->get() : "[" + std::to_string(index) + "]";
      out.emplace_back(*t, element_path, *diag_);
    }
    ++index;
  }
  return out;
}

void Reader::finish() {
  for (const auto& [key, node] : *table_) {
    if (known_.count(key.str())) continue;
    diag_->add(line_of(node), key_path(key.str()), describe(node), "unknown key");
  }
}

}  // namespace hapfluid::config::detail
