// The log every process writes: levels filter, one message per write however many threads log,
// and the journal's priority prefix on every line of a message.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "hapfluid/config/log.hpp"

namespace log = hapfluid::log;

namespace {

// Runs `body` with stderr sent to a file; returns what was written.
template <class Body>
std::string captured_stderr(Body body) {
  const auto file = std::filesystem::temp_directory_path() / ("hapfluid_log_" + std::to_string(getpid()));
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  const int saved = ::dup(STDERR_FILENO);
  ::dup2(fd, STDERR_FILENO);
  ::close(fd);
  body();
  ::dup2(saved, STDERR_FILENO);
  ::close(saved);
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  std::filesystem::remove(file);
  return s.str();
}

struct LogTest : ::testing::Test {
  void SetUp() override {
    saved_ = log::level();
    log::set_tool("tester");
  }
  void TearDown() override { log::set_level(saved_); }
  log::Level saved_{};
};

}  // namespace

TEST_F(LogTest, MessagesBelowTheLevelAreDropped) {
  log::set_level(log::Level::warning);
  const std::string out = captured_stderr([] {
    log::debug("d");
    log::info("i %d", 1);
    log::notice("n");
    log::warning("w %s", "two");
    log::error("e");
    log::Line(log::Level::info) << "line info";
    log::Line(log::Level::error) << "line " << std::fixed << std::setprecision(2) << 1.5;
  });
  EXPECT_EQ(out, "tester: w two\ntester: e\ntester: line 1.50\n");
  EXPECT_FALSE(log::enabled(log::Level::notice));
  EXPECT_TRUE(log::enabled(log::Level::warning));
}

TEST_F(LogTest, LevelsAreNamedAsSyslogPriorities) {
  for (auto [name, level, priority] : {std::tuple{"error", log::Level::error, 3}, {"warning", log::Level::warning, 4},
                                       {"notice", log::Level::notice, 5}, {"info", log::Level::info, 6},
                                       {"debug", log::Level::debug, 7}}) {
    EXPECT_EQ(log::parse_level(name), level);
    EXPECT_STREQ(log::to_string(level), name);
    EXPECT_EQ(static_cast<int>(level), priority);
  }
  EXPECT_FALSE(log::parse_level("warn"));
  EXPECT_FALSE(log::parse_level("INFO"));
  EXPECT_FALSE(log::parse_level(""));
}

TEST_F(LogTest, AMessageOfSeveralLinesKeepsItsLinesAndTheJournalGetsThePriorityOnEach) {
  EXPECT_EQ(log::detail::format(log::Level::error, "tool", false, "bad scene:\n  a\n  b\n"),
            "tool: bad scene:\n  a\n  b\n");
  EXPECT_EQ(log::detail::format(log::Level::error, "tool", true, "bad scene:\n  a\n  b"),
            "<3>tool: bad scene:\n<3>  a\n<3>  b\n");
  EXPECT_EQ(log::detail::format(log::Level::info, "tool", true, "one"), "<6>tool: one\n");
  EXPECT_EQ(log::detail::format(log::Level::warning, "", false, "no tool"), "no tool\n");
}

TEST_F(LogTest, LinesOfManyThreadsNeverInterleave) {
  log::set_level(log::Level::info);
  constexpr int kThreads = 4, kMessages = 2000;
  const std::string out = captured_stderr([] {
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t)
      threads.emplace_back([t] {
        // Long enough that a torn write would show: more than one stdio buffer's worth per line.
        const std::string filler(600, static_cast<char>('a' + t));
        for (int k = 0; k < kMessages; ++k) log::info("thread %d message %d %s end", t, k, filler.c_str());
      });
    for (auto& th : threads) th.join();
  });
  const std::regex line(R"(tester: thread (\d) message (\d+) ([a-d])\3{599} end)");
  std::vector<int> next(kThreads, 0);
  std::istringstream lines(out);
  std::string text;
  int count = 0;
  while (std::getline(lines, text)) {
    std::smatch m;
    ASSERT_TRUE(std::regex_match(text, m, line)) << "torn line: " << text.substr(0, 80);
    const int t = std::stoi(m[1]);
    ASSERT_EQ(m[3].str()[0], 'a' + t);
    EXPECT_EQ(std::stoi(m[2]), next[t]++) << "thread " << t << " out of order";
    ++count;
  }
  EXPECT_EQ(count, kThreads * kMessages);
}
