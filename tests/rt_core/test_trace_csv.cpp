// The trace CSV rows haptic-trace writes from the shared trace ring, which another process fills:
// a row must come out for any record, whatever its values. This test is built with UBSan and
// -fno-sanitize-recover, so arithmetic on the record that is undefined aborts it.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "hapfluid/rt/trace_csv.hpp"

namespace {

std::vector<std::string> row_of(const hapfluid::shm::TraceRecord& record) {
  std::FILE* file = std::tmpfile();
  hapfluid::rt::write_trace_row(file, record, 1);
  std::rewind(file);
  char text[1024] = {};
  EXPECT_NE(std::fgets(text, sizeof text, file), nullptr);
  std::fclose(file);
  std::vector<std::string> columns(1);
  for (const char* c = text; *c && *c != '\n'; ++c) {
    if (*c == ',') columns.emplace_back();
    else columns.back() += *c;
  }
  return columns;
}

constexpr int kWakeLatencyColumn = 3;  // tick, scheduled_ns, wake_ns, wake_latency_ns, ...

}  // namespace

TEST(TraceCsv, WakeLatencyIsTheWakeTimeMinusTheScheduledTime) {
  hapfluid::shm::TraceRecord record{};
  record.scheduled_ns = 2'000'000;
  record.wake_ns = 2'000'500;
  EXPECT_EQ(row_of(record)[kWakeLatencyColumn], "500");
  record.wake_ns = 1'999'000;  // a wake before its time reads as negative
  EXPECT_EQ(row_of(record)[kWakeLatencyColumn], "-1000");
}

TEST(TraceCsv, StampsAnotherProcessMadeUpGiveARowWithTheLatencyModulo2To64) {
  // As signed numbers, 2^63 - 1 overflows; the column is the difference modulo 2^64.
  hapfluid::shm::TraceRecord record{};
  record.scheduled_ns = 1;
  record.wake_ns = 1ull << 63;
  const std::vector<std::string> row = row_of(record);
  ASSERT_EQ(row.size(), 12u + 13u);
  EXPECT_EQ(row[kWakeLatencyColumn], "9223372036854775807");
  record.scheduled_ns = 1ull << 63;
  record.wake_ns = 1;
  EXPECT_EQ(row_of(record)[kWakeLatencyColumn], "-9223372036854775807");
}
