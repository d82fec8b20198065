// A minimal JSON reader for the shared test vectors (no JSON library is a dependency of the
// project). Objects, arrays, strings without escapes beyond \" and \\, numbers, true/false/null.
#pragma once

#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace json_mini {

struct Value {
  enum Kind { null, boolean, number, string, array, object } kind = null;
  double num = 0;
  bool flag = false;
  std::string str;
  std::vector<Value> items;
  std::map<std::string, Value> fields;

  const Value& operator[](const std::string& key) const {
    auto it = fields.find(key);
    if (it == fields.end()) throw std::runtime_error("json: missing key " + key);
    return it->second;
  }
  const Value& operator[](std::size_t i) const { return items.at(i); }
  bool has(const std::string& key) const { return fields.count(key) != 0; }
  std::size_t size() const { return kind == array ? items.size() : fields.size(); }
};

class Parser {
 public:
  explicit Parser(std::string text) : s_(std::move(text)) {}
  Value parse() {
    Value v = value();
    ws();
    if (i_ != s_.size()) fail("trailing characters");
    return v;
  }

 private:
  std::string s_;
  std::size_t i_ = 0;

  [[noreturn]] void fail(const char* what) {
    throw std::runtime_error(std::string("json: ") + what + " at offset " + std::to_string(i_));
  }
  void ws() { while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_; }
  bool eat(char c) { ws(); if (i_ < s_.size() && s_[i_] == c) { ++i_; return true; } return false; }
  Value value() {
    ws();
    if (i_ >= s_.size()) fail("unexpected end");
    Value v;
    char c = s_[i_];
    if (c == '{') {
      ++i_;
      v.kind = Value::object;
      if (eat('}')) return v;
      do {
        ws();
        std::string key = str();
        if (!eat(':')) fail("expected ':'");
        v.fields[key] = value();
      } while (eat(','));
      if (!eat('}')) fail("expected '}'");
    } else if (c == '[') {
      ++i_;
      v.kind = Value::array;
      if (eat(']')) return v;
      do v.items.push_back(value()); while (eat(','));
      if (!eat(']')) fail("expected ']'");
    } else if (c == '"') {
      v.kind = Value::string;
      v.str = str();
    } else if (s_.compare(i_, 4, "true") == 0) { v.kind = Value::boolean; v.flag = true; i_ += 4; }
    else if (s_.compare(i_, 5, "false") == 0) { v.kind = Value::boolean; i_ += 5; }
    else if (s_.compare(i_, 4, "null") == 0) { i_ += 4; }
    else {
      char* end = nullptr;
      v.kind = Value::number;
      v.num = std::strtod(s_.c_str() + i_, &end);
      if (end == s_.c_str() + i_) fail("bad number");
      i_ = static_cast<std::size_t>(end - s_.c_str());
    }
    return v;
  }
  std::string str() {
    if (s_[i_] != '"') fail("expected string");
    std::string out;
    for (++i_; i_ < s_.size() && s_[i_] != '"'; ++i_) {
      if (s_[i_] == '\\') ++i_;
      out += s_[i_];
    }
    ++i_;
    return out;
  }
};

inline Value load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::stringstream ss;
  ss << in.rdbuf();
  return Parser(ss.str()).parse();
}

inline std::vector<unsigned char> hex(const std::string& h) {
  std::vector<unsigned char> out;
  for (std::size_t i = 0; i + 1 < h.size(); i += 2)
    out.push_back(static_cast<unsigned char>(std::stoul(h.substr(i, 2), nullptr, 16)));
  return out;
}

}  // namespace json_mini
