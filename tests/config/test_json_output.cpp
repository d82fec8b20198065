// The JSON every executable writes: records carry the build, text is always valid UTF-8 JSON,
// and a file is either whole or absent.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

#include "hapfluid/config/build_id.hpp"
#include "hapfluid/config/json_output.hpp"

namespace config = hapfluid::config;

namespace {

std::filesystem::path fresh_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / (name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string read(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST(JsonOutput, BenchRecordNamesTheBenchAndTheBuildInOrder) {
  const config::Json r = config::bench_record("bench_x", {{"particles", 32000}}, {{"ms_per_step", 12.5}});
  std::vector<std::string> keys;
  for (const auto& item : r.items()) keys.push_back(item.key());
  EXPECT_EQ(keys, (std::vector<std::string>{"bench", "build_id", "params", "metrics"}));
  EXPECT_EQ(r["build_id"], config::build_id());
  EXPECT_EQ(r["params"]["particles"], 32000);
}

TEST(JsonOutput, TextIsValidJsonWhateverTheStringsAndNumbersHold) {
  config::Json j;
  j["path"] = std::string("caf\xe9/\"scene\"\\.toml");  // Latin-1 byte, quote, backslash
  j["nan"] = std::nan("");
  j["inf"] = HUGE_VAL;
  const std::string text = config::json_text(j);
  ASSERT_EQ(text.back(), '\n');
  const config::Json back = config::Json::parse(text);  // throws if the text is not JSON
  EXPECT_EQ(back["path"], "caf\xef\xbf\xbd/\"scene\"\\.toml");  // U+FFFD for the bad byte
  EXPECT_TRUE(back["nan"].is_null());
  EXPECT_TRUE(back["inf"].is_null());
  EXPECT_EQ(config::json_line(j).find('\n'), std::string::npos);
}

TEST(JsonOutput, AtomicWriteLeavesTheWholeFileAndNoTemporary) {
  const auto dir = fresh_dir("hapfluid_json_output");
  const auto file = dir / "stats.json";
  config::write_json_atomically(file, {{"steps", 1}});
  config::write_json_atomically(file, {{"steps", 2}});
  EXPECT_EQ(config::Json::parse(read(file))["steps"], 2);
  EXPECT_FALSE(std::filesystem::exists(dir / "stats.json.part"));
  std::filesystem::remove_all(dir);
}

TEST(JsonOutput, AFileThatCannotBeWrittenIsNamed) {
  const auto dir = fresh_dir("hapfluid_json_output_missing");
  const auto file = dir / "no_such_folder" / "stats.json";
  try {
    config::write_json_atomically(file, {{"steps", 1}});
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "no_such_folder" / "stats.json.part").string()), std::string::npos)
        << e.what();
  }
  std::filesystem::remove_all(dir);
}
