// Who may write a channel. Only its writer may write a segment (mode 0640); a reader attaches
// only to a segment owned by its own user or root that no one else may write, and says whose it
// refused. A name that another local user created first neither hijacks nor blocks the rig: the
// writer takes a fallback name and the readers find it. Another owner is made by chown to uid
// 65534 (nobody), which needs root: those tests skip elsewhere.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <string>

#include "hapfluid/shm/channel.hpp"

using namespace hapfluid::shm;

namespace {

constexpr uid_t kNobody = 65534;

std::string unique_name(const char* what) { return "/hapfluid-test-" + std::to_string(::getpid()) + "." + what; }

struct Sample {
  std::uint64_t value;
  double payload[5];
};

std::string attach_error(const std::string& name) {
  try {
    LatestReader::attach(name, ChannelKind::sim_samples, sizeof(Sample));
    return {};
  } catch (const ShmError& e) {
    return e.what();
  }
}

void change_owner(const std::string& name, uid_t uid) {
  int fd = ::shm_open(name.c_str(), O_RDONLY, 0);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::fchown(fd, uid, static_cast<gid_t>(-1)), 0);
  ::close(fd);
}

}  // namespace

TEST(ShmOwnership, WriterRefusesAModeThatLetsOthersWrite) {
  // 0660 let every member of the group write sim_samples and so inject wrenches.
  WriterOptions options;
  options.mode = 0660;
  try {
    LatestWriter::create(unique_name("mode0660"), ChannelKind::sim_samples, sizeof(Sample), 4, options);
    FAIL() << "expected ShmError";
  } catch (const ShmError& e) {
    EXPECT_NE(std::string(e.what()).find("mode 0660"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("use 0640"), std::string::npos) << e.what();
  }
}

TEST(ShmOwnership, ReaderRefusesASegmentOthersMayWrite) {
  auto name = unique_name("groupwritable");
  auto writer = LatestWriter::create(name, ChannelKind::sim_samples, sizeof(Sample));
  int fd = ::shm_open(name.c_str(), O_RDONLY, 0);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::fchmod(fd, 0660), 0);
  ::close(fd);
  const std::string error = attach_error(name);
  EXPECT_NE(error.find("has mode 0660"), std::string::npos) << error;
  writer.close();
}

TEST(ShmOwnership, ReaderRefusesASegmentOfAnotherUserAndNamesTheOwner) {
  if (::geteuid() != 0) GTEST_SKIP() << "chown to another user needs root";
  auto name = unique_name("foreignowner");
  auto writer = LatestWriter::create(name, ChannelKind::sim_samples, sizeof(Sample));
  writer.publish(Sample{666, {}});
  change_owner(name, kNobody);
  const std::string error = attach_error(name);
  EXPECT_NE(error.find("the segment is owned by uid 65534"), std::string::npos) << error;
  EXPECT_NE(error.find("refusing it"), std::string::npos) << error;
  EXPECT_NE(error.find("rm /dev/shm" + name), std::string::npos) << "the fix is named: " << error;
  writer.close();
}

TEST(ShmOwnership, AReaderOfItsOwnUserTrustsTheWritersUserItNamesAndNoOther) {
  // haptic-dashboard's observer runs as its own user: it names the services' user, whose
  // segments it then reads; a third user's segment is still refused, naming all it would take.
  if (::geteuid() != 0) GTEST_SKIP() << "chown to another user needs root";
  auto name = unique_name("writersuser");
  auto writer = LatestWriter::create(name, ChannelKind::sim_samples, sizeof(Sample));
  writer.publish(Sample{7, {}});
  change_owner(name, kNobody);
  trust_writer_uid(kNobody);
  Sample got{};
  EXPECT_EQ(LatestReader::attach(name, ChannelKind::sim_samples, sizeof(Sample)).try_read(got), ReadResult::ok);
  EXPECT_EQ(got.value, 7u);
  trust_writer_uid(kNobody - 1);
  const std::string error = attach_error(name);
  EXPECT_NE(error.find("owned by uid 65534"), std::string::npos) << error;
  EXPECT_NE(error.find("or the writers' user (uid 65533"), std::string::npos) << error;
  trust_writer_uid(static_cast<uid_t>(-1));
  writer.close();
}

TEST(ShmOwnership, SquattedNameNeitherHijacksNorBlocksTheRig) {
  // Another user created the channel's name before the services started, with a well-formed
  // header and a record of its own. The writer must start anyway, and the reader must get the
  // writer's records, never the squatter's.
  if (::geteuid() != 0) GTEST_SKIP() << "chown to another user needs root";
  auto name = unique_name("squatted");
  auto squatter = LatestWriter::create(name, ChannelKind::sim_samples, sizeof(Sample));
  squatter.publish(Sample{666, {}});
  change_owner(name, kNobody);

  testing::internal::CaptureStderr();
  auto writer = LatestWriter::create(name, ChannelKind::sim_samples, sizeof(Sample));
  const std::string said = testing::internal::GetCapturedStderr();
  EXPECT_NE(said.find("held by uid 65534"), std::string::npos) << said;
  EXPECT_NE(said.find("rm /dev/shm" + name), std::string::npos) << "the fix is named: " << said;
  EXPECT_NE(writer.segment().name(), name) << "written under a fallback name";
  EXPECT_EQ(writer.segment().name().rfind(name + ".", 0), 0u) << writer.segment().name();
  struct stat st {};
  ASSERT_EQ(::stat(("/dev/shm" + name).c_str(), &st), 0) << "the writer removed another user's segment";
  EXPECT_EQ(st.st_uid, kNobody);
  writer.publish(Sample{42, {}});

  auto reader = LatestReader::attach(name, ChannelKind::sim_samples, sizeof(Sample));
  EXPECT_EQ(reader.segment().name(), writer.segment().name());
  Sample out{};
  ASSERT_EQ(reader.try_read(out), ReadResult::ok);
  EXPECT_EQ(out.value, 42u) << "the squatter's record reached the reader";
  EXPECT_EQ(reader.check_liveness(monotonic_ns(), 0), WriterStatus::live);

  // A restart while the squat persists: the old fallback goes, a new one is found.
  writer.close();
  EXPECT_EQ(reader.check_liveness(monotonic_ns(), 0), WriterStatus::closed);
  auto restarted = LatestWriter::create(name, ChannelKind::sim_samples, sizeof(Sample));
  restarted.publish(Sample{43, {}});
  auto fresh = LatestReader::attach(name, ChannelKind::sim_samples, sizeof(Sample));
  ASSERT_EQ(fresh.try_read(out), ReadResult::ok);
  EXPECT_EQ(out.value, 43u);
  restarted.close();
  squatter.close();
}

TEST(ShmOwnership, WriterReplacesItsOwnGroupWritableLeftover) {
  // A segment of this user from an older build (mode 0660) is ours to replace, not a squat.
  auto name = unique_name("ownleftover");
  int fd = ::shm_open(name.c_str(), O_RDWR | O_CREAT | O_EXCL, 0660);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::fchmod(fd, 0660), 0);
  ASSERT_EQ(::ftruncate(fd, 4096), 0);
  ::close(fd);
  auto writer = LatestWriter::create(name, ChannelKind::sim_samples, sizeof(Sample));
  EXPECT_EQ(writer.segment().name(), name);
  writer.publish(Sample{7, {}});
  auto reader = LatestReader::attach(name, ChannelKind::sim_samples, sizeof(Sample));
  Sample out{};
  ASSERT_EQ(reader.try_read(out), ReadResult::ok);
  EXPECT_EQ(out.value, 7u);
  writer.close();
}
