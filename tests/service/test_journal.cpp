// The state journal (restart without loss): exact round trip, atomic replacement (also when the
// writer is SIGKILLed mid-stream), and a clear refusal of every kind of bad file.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "usv_fdi/dds_service/journal.hpp"
#include "usv_fdi/io/jsonl.hpp"

namespace usvfdi::dds_service {
namespace {

namespace fs = std::filesystem;

/// A directory of its own, removed at the end.
struct TempDir {
  std::string path;
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path =
        ::testing::TempDir() + "usv_fdi_journal_" + info->name() + "_" + std::to_string(::getpid());
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
};

std::string slurp(const std::string& p) {
  std::ifstream f(p, std::ios::binary);
  std::ostringstream os;
  os << f.rdbuf();
  return os.str();
}

void spit(const std::string& p, const std::string& text) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f << text;
}

FaultEvent event(Sensor s, FaultState st, std::uint64_t seq) {
  FaultEvent e;
  e.sensor = s;
  e.state = st;
  e.kind = FaultKind::kBias;
  e.c_a = 0.1;  // not exactly representable: the round trip must still be exact
  e.c_g = 0.9876543210987654;
  e.statistic = 1e-300;
  e.threshold = 6.0;
  e.onset_time = kNaN;
  e.detection_time = 20.24;
  e.t = 41.4;
  e.sequence = seq;
  e.A << -0.883018693291188, -0.43861208856774481, -1.5517361741892823, 1e17;
  e.message = "J_N 8.3 > 6 \"quoted\", back\\slash, new\nline, tab\t, UTF-8: \xc3\xa9\xe2\x82\xac";
  return e;
}

bool same_double(double a, double b) {
  return (std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0;
}

void expect_same(const FaultEvent& a, const FaultEvent& b) {
  EXPECT_EQ(a.sensor, b.sensor);
  EXPECT_EQ(a.state, b.state);
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.sequence, b.sequence);
  for (auto [x, y] : {std::pair{a.c_a, b.c_a},
                      {a.c_g, b.c_g},
                      {a.statistic, b.statistic},
                      {a.threshold, b.threshold},
                      {a.onset_time, b.onset_time},
                      {a.detection_time, b.detection_time},
                      {a.t, b.t}}) {
    EXPECT_TRUE(same_double(x, y)) << x << " vs " << y;
  }
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(same_double(a.A(i / 2, i % 2), b.A(i / 2, i % 2)));
  EXPECT_EQ(a.message, b.message);
}

/// FNV-1a 64 (the format's checksum), written independently of the implementation.
std::string fnv(const std::string& s) {
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

/// Replaces `from` by `to` in a serialised file and re-signs it (a well-formed file with
/// different content).
std::string edit_and_resign(const std::string& text, const std::string& from,
                            const std::string& to) {
  const std::string marker = "\n  \"checksum\": \"fnv1a64:";
  std::string body = text.substr(0, text.rfind(marker) + 1);
  const auto at = body.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  body.replace(at, from.size(), to);
  return body + marker.substr(1) + fnv(body) + "\"\n}\n";
}

TEST(StateJournal, RoundTripIsExactIncludingNaNAndStrings) {
  const std::vector<FaultEvent> in = {
      event(Sensor::kAccelerometer, FaultState::kRaised, 1),
      event(Sensor::kGyro, FaultState::kClearedUnacknowledged, 7),
      event(Sensor::kUnknown, FaultState::kAcknowledged, 12345678901234ull)};
  const std::string text = StateJournal::serialise(257000001, in, 1795449401.3051717);
  StateJournal::Contents out;
  std::string err;
  ASSERT_TRUE(StateJournal::parse(text, 257000001, &out, &err)) << err << "\n" << text;
  ASSERT_EQ(out.events.size(), 3u);
  for (int i = 0; i < 3; ++i) expect_same(in[i], out.events[i]);
  EXPECT_DOUBLE_EQ(out.written, 1795449401.3051717);
  // An empty state (no fault ever) is a valid file too.
  ASSERT_TRUE(StateJournal::parse(StateJournal::serialise(1, {}, 0.0), 1, &out, &err)) << err;
  EXPECT_TRUE(out.events.empty());
}

TEST(StateJournal, AFileOfThePreviousLayoutIsRead) {
  // Written by the version before the one serialisation of a FaultEvent (its fields spread
  // over three lines with spaces after the colons): a vessel's state survives the upgrade.
  std::string body =
      "{\n  \"format\": \"usv-fdi fault state\",\n  \"version\": 1,\n  \"mmsi\": 257000009,\n"
      "  \"written\": 1795449401.5,\n  \"instances\": [\n"
      "    {\"sensor\": \"gyro\", \"state\": \"raised\", \"kind\": \"bias\", \"sequence\": 3, "
      "\"incarnation\": 17,\n"
      "     \"c_a\": 0.25, \"c_g\": 0.96875, \"statistic\": 14.5, \"threshold\": 6,\n"
      "     \"onset_time\": 20, \"detection_time\": 20.5, \"stamp\": 21.5,\n"
      "     \"a\": [-0.5, 0.25, 0.125, -1], \"message\": \"gyro bias\"}\n  ],\n";
  const std::string text = body + "  \"checksum\": \"fnv1a64:" + fnv(body) + "\"\n}\n";
  StateJournal::Contents out;
  std::string err;
  ASSERT_TRUE(StateJournal::parse(text, 257000009, &out, &err)) << err;
  ASSERT_EQ(out.events.size(), 1u);
  const FaultEvent& e = out.events[0];
  EXPECT_EQ(e.sensor, Sensor::kGyro);
  EXPECT_EQ(e.state, FaultState::kRaised);
  EXPECT_EQ(e.sequence, 3u);
  EXPECT_EQ(e.incarnation, 17u);
  EXPECT_EQ(e.c_g, 0.96875);
  EXPECT_EQ(e.t, 21.5);
  EXPECT_EQ(e.A(1, 1), -1.0);
  EXPECT_EQ(e.message, "gyro bias");
  // And what this version writes is one line per instance, the replay's and monitor's form.
  const std::string now = StateJournal::serialise(257000009, out.events, 1795449402.0);
  EXPECT_NE(now.find("    {" + io::fault_event_fields(e, 17) + "}\n"), std::string::npos) << now;
}

TEST(StateJournal, RecordReplacesTheFileAtomicallyAndKeepsTheLatestOfEachInstance) {
  TempDir d;
  const std::string path = StateJournal::path_for(d.path, 257000002);
  EXPECT_EQ(fs::path(path).filename(), "usv-fdi-257000002.state.json");
  StateJournal j(path, 257000002);
  StateJournal::Contents c;
  std::string err;
  EXPECT_EQ(StateJournal::load(path, 257000002, &c, &err), StateJournal::LoadResult::kMissing);
  ASSERT_TRUE(j.record(event(Sensor::kGyro, FaultState::kRaised, 1))) << j.last_error();
  ASSERT_TRUE(j.record(event(Sensor::kAccelerometer, FaultState::kRaised, 1)));
  ASSERT_TRUE(j.record(event(Sensor::kGyro, FaultState::kClearedUnacknowledged, 2)));
  ASSERT_EQ(StateJournal::load(path, 257000002, &c, &err), StateJournal::LoadResult::kLoaded)
      << err;
  ASSERT_EQ(c.events.size(), 2u);
  EXPECT_EQ(c.events[0].sensor, Sensor::kAccelerometer);
  EXPECT_EQ(c.events[1].sensor, Sensor::kGyro);
  EXPECT_EQ(c.events[1].sequence, 2u);
  EXPECT_EQ(c.events[1].state, FaultState::kClearedUnacknowledged);
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  EXPECT_EQ(j.saves(), 3u);

  // A save that cannot complete leaves the previous file as it was and says why.
  const std::string before = slurp(path);
  const std::string dir_path = d.path + "/a_directory";
  fs::create_directories(dir_path);
  std::string why;
  EXPECT_FALSE(StateJournal::write_atomic(dir_path, "x", &why));
  EXPECT_NE(why.find("cannot rename"), std::string::npos) << why;
  EXPECT_FALSE(fs::exists(dir_path + ".tmp"));
  StateJournal broken(d.path + "/no/such/dir/f.json", 1);
  EXPECT_FALSE(broken.record(event(Sensor::kGyro, FaultState::kRaised, 1)));
  EXPECT_NE(broken.last_error().find("cannot create " + d.path + "/no/such/dir/f.json.tmp"),
            std::string::npos)
      << broken.last_error();
  EXPECT_EQ(slurp(path), before);
}

TEST(StateJournal, AWriterKilledMidStreamLeavesAWholeFile) {
  // GIVEN a child process that rewrites the state file as fast as it can, alternating two
  // states (one of them with a long message, so a torn write would be visible)
  TempDir d;
  const std::string path = StateJournal::path_for(d.path, 42);
  FaultEvent small = event(Sensor::kGyro, FaultState::kRaised, 1);
  FaultEvent big = event(Sensor::kGyro, FaultState::kClearedUnacknowledged, 2);
  big.message = std::string(60000, 'x');
  ASSERT_TRUE(StateJournal(path, 42).record(small));
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    StateJournal j(path, 42);
    for (int k = 0;; ++k) j.record(k % 2 ? small : big);
  }
  // WHEN the parent reads it meanwhile and then kills the writer with SIGKILL
  int loads = 0;
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(400);
  while (std::chrono::steady_clock::now() < end) {
    StateJournal::Contents c;
    std::string err;
    // THEN every read sees one whole state or the other, never a mix
    ASSERT_EQ(StateJournal::load(path, 42, &c, &err), StateJournal::LoadResult::kLoaded) << err;
    ASSERT_EQ(c.events.size(), 1u);
    ASSERT_TRUE(c.events[0].sequence == 1 || c.events[0].sequence == 2);
    ++loads;
  }
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  // AND after the kill the file is whole (a leftover .tmp is the sidecar's to remove)
  StateJournal::Contents c;
  std::string err;
  ASSERT_EQ(StateJournal::load(path, 42, &c, &err), StateJournal::LoadResult::kLoaded) << err;
  EXPECT_GT(loads, 10);
}

struct BadCase {
  std::string name;
  std::string text;
  std::string expect;  ///< in the error
};

TEST(StateJournal, BadFilesAreRefusedWithWhatIsWrong) {
  const std::string good = StateJournal::serialise(
      257000003, {event(Sensor::kGyro, FaultState::kRaised, 3)}, 1795449401.0);
  std::string flipped = good;
  flipped[flipped.find("\"raised\"") + 1] = 'R';
  const std::vector<BadCase> cases = {
      {"empty", "", "the file is empty"},
      {"truncated", good.substr(0, good.size() / 2), "no checksum line"},
      {"not json", "hello\n", "no checksum line"},
      {"bit flip", flipped, "checksum mismatch"},
      {"version", edit_and_resign(good, "\"version\": 1", "\"version\": 2"),
       "version 2 (this usv-fdi reads version 1 only)"},
      {"format", edit_and_resign(good, "usv-fdi fault state", "something else"),
       "\"format\" is \"something else\""},
      {"other vessel", edit_and_resign(good, "257000003", "257000004"),
       "the file is for MMSI 257000004, this sidecar watches 257000003"},
      {"unknown field", edit_and_resign(good, "\"kind\"", "\"colour\":1,\"kind\""),
       "unknown field \"colour\""},
      {"sensor", edit_and_resign(good, "\"gyro\"", "\"compass\""), "unknown sensor \"compass\""},
      {"state", edit_and_resign(good, "\"raised\"", "\"panicking\""),
       "unknown state \"panicking\""},
      {"sequence", edit_and_resign(good, "\"sequence\":3", "\"sequence\":-3"),
       "\"sequence\" = -3 is not a non-negative integer"},
      {"missing", edit_and_resign(good, "\"c_a\":0.10000000000000001,", ""), "\"c_a\" is missing"},
      {"a", edit_and_resign(good, "\"a\":[", "\"a\":[1,"), "\"a\" must be a list of 4"},
      {"number", edit_and_resign(good, "\"threshold\":6", "\"threshold\":\"six\""),
       "\"threshold\" = six is not a number"},
      {"syntax", edit_and_resign(good, "\"instances\": [", "\"instances\": [[}"),
       "not valid JSON at line"},
      {"twice",
       edit_and_resign(good, "\n  ],",
                       ",\n" +
                           good.substr(good.find("    {\"sensor\""),
                                       good.find("}\n  ],") + 1 - good.find("    {\"sensor\"")) +
                           "\n  ],"),
       "sensor gyro appears twice"},
  };
  for (const BadCase& c : cases) {
    StateJournal::Contents out;
    std::string err;
    EXPECT_FALSE(StateJournal::parse(c.text, 257000003, &out, &err)) << c.name << "\n" << c.text;
    EXPECT_NE(err.find(c.expect), std::string::npos) << c.name << ": " << err;
  }
  // The good file parses (the cases above differ from it in one thing each).
  StateJournal::Contents out;
  std::string err;
  EXPECT_TRUE(StateJournal::parse(good, 257000003, &out, &err)) << err;
}

TEST(StateJournal, LoadNamesTheFileAndSetAsideKeepsTheBadOne) {
  TempDir d;
  const std::string path = StateJournal::path_for(d.path, 7);
  spit(path, "{ not a state file");
  StateJournal::Contents c;
  std::string err;
  ASSERT_EQ(StateJournal::load(path, 7, &c, &err), StateJournal::LoadResult::kError);
  EXPECT_EQ(err.rfind(path + ": ", 0), 0u) << err;
  std::string why;
  const std::string aside = StateJournal::set_aside(path, &why);
  ASSERT_FALSE(aside.empty()) << why;
  EXPECT_EQ(aside.rfind(path + ".corrupt-", 0), 0u) << aside;
  EXPECT_FALSE(fs::exists(path));
  EXPECT_EQ(slurp(aside), "{ not a state file");
  // A directory where the file should be cannot be read: an error, not "missing".
  fs::create_directories(path);
  EXPECT_EQ(StateJournal::load(path, 7, &c, &err), StateJournal::LoadResult::kError);
  EXPECT_NE(err.find(path), std::string::npos) << err;
}

}  // namespace
}  // namespace usvfdi::dds_service
