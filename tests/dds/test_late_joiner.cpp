// A late-joining FaultEvent reader in another process must receive the latest state of every
// instance written before it joined (RELIABLE + TRANSIENT_LOCAL + KEEP_LAST 1), and the publisher
// must shut down cleanly on SIGTERM.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "process.hpp"
#include "test_env.hpp"
#include "usv_fdi/dds/profiles.hpp"

namespace usvfdi::dds::test {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;

struct Instance {
  unsigned state = 0;
  unsigned long long sequence = 0;
  unsigned samples = 0;
};

std::map<std::pair<unsigned, unsigned>, Instance> parse_instances(const std::string& out) {
  static const std::regex line_re(
      R"(^instance mmsi=(\d+) sensor=(\d+) state=(\d+) kind=\d+ sequence=(\d+) samples=(\d+) )");
  std::map<std::pair<unsigned, unsigned>, Instance> result;
  std::istringstream in(out);
  std::string line;
  while (std::getline(in, line)) {
    std::smatch m;
    if (!std::regex_search(line, m, line_re)) continue;
    Instance i;
    i.state = static_cast<unsigned>(std::stoul(m[3]));
    i.sequence = std::stoull(m[4]);
    i.samples = static_cast<unsigned>(std::stoul(m[5]));
    result[{static_cast<unsigned>(std::stoul(m[1])), static_cast<unsigned>(std::stoul(m[2]))}] = i;
  }
  return result;
}

class LateJoinerTest : public ::testing::TestWithParam<const char*> {};

TEST_P(LateJoinerTest, ReaderGetsLatestStateOfEveryInstance) {
  const std::string participant = GetParam();
  const std::string domain = std::to_string(test_domain_id());
  const std::string partition = unique_partition();
  constexpr unsigned kBase = 257000000;
  const std::vector<std::string> common = {
      "--profiles", kProfilesFile, "--domain", domain, "--participant-profile",
      participant,  "--partition", partition};

  std::vector<std::string> pub_args = {kProbe, "publish-faults"};
  pub_args.insert(pub_args.end(), common.begin(), common.end());
  for (const char* a : {"--vessels", "3", "--sensors", "2", "--state", "1", "--rewrite-state", "4",
                        "--mmsi-base", "257000000", "--timeout", "30"}) {
    pub_args.emplace_back(a);
  }
  ChildProcess publisher(pub_args);
  const auto published = publisher.read_line(milliseconds(10000));
  ASSERT_TRUE(published.has_value()) << "publisher did not report (exit "
                                     << publisher.wait_exit(milliseconds(0)).value_or(-1) << ")";
  EXPECT_EQ(*published, "published instances=6 writes=7");

  // Join late: the samples are only available from the writer's TRANSIENT_LOCAL history.
  std::this_thread::sleep_for(milliseconds(1000));
  ASSERT_TRUE(publisher.running());

  std::vector<std::string> read_args = {kProbe, "read-faults"};
  read_args.insert(read_args.end(), common.begin(), common.end());
  for (const char* a : {"--expect", "6", "--timeout", "15", "--settle-ms", "500"}) {
    read_args.emplace_back(a);
  }
  ChildProcess reader(read_args);
  const std::string out = reader.read_all(milliseconds(25000));
  const auto reader_exit = reader.wait_exit(milliseconds(5000));
  ASSERT_TRUE(reader_exit.has_value()) << "reader did not exit";
  EXPECT_EQ(*reader_exit, 0) << out;

  const auto instances = parse_instances(out);
  EXPECT_EQ(instances.size(), 6u) << out;
  for (unsigned v = 0; v < 3; ++v) {
    for (unsigned s = 0; s < 2; ++s) {
      const auto it = instances.find({kBase + v, s});
      ASSERT_NE(it, instances.end()) << "missing mmsi " << kBase + v << " sensor " << s << "\n"
                                     << out;
      const bool rewritten = v == 0 && s == 0;
      EXPECT_EQ(it->second.state, rewritten ? 4u : 1u) << out;
      EXPECT_EQ(it->second.sequence, rewritten ? 2u : 1u) << out;
      // KEEP_LAST 1 on the writer: only the latest sample of each instance is replayed.
      EXPECT_EQ(it->second.samples, 1u) << out;
    }
  }

  publisher.signal(SIGTERM);
  const auto pub_exit = publisher.wait_exit(milliseconds(2000));
  ASSERT_TRUE(pub_exit.has_value()) << "publisher still running 2 s after SIGTERM";
  EXPECT_EQ(*pub_exit, 0);
  EXPECT_EQ(publisher.read_all(milliseconds(1000)), "stopping reason=signal\n");
}

// Both test transports keep all traffic on this host: UDPv4 bound to 127.0.0.1 with unicast
// discovery, and shared memory only. (usv_fdi_participant, the builtin SHM + UDPv4 multicast
// default, also passes here but sends discovery multicast on every interface.)
INSTANTIATE_TEST_SUITE_P(Participants, LateJoinerTest,
                         ::testing::Values(profiles::kParticipantLoopback,
                                           profiles::kParticipantShm),
                         [](const ::testing::TestParamInfo<const char*>& info) {
                           return std::string(info.param) == profiles::kParticipantShm
                                      ? std::string("shm")
                                      : std::string("udp_loopback");
                         });

TEST(LateJoinerTest, ReaderTimesOutWithoutPublisher) {
  const std::vector<std::string> args = {kProbe,
                                         "read-faults",
                                         "--profiles",
                                         kProfilesFile,
                                         "--domain",
                                         std::to_string(test_domain_id()),
                                         "--participant-profile",
                                         profiles::kParticipantLoopback,
                                         "--partition",
                                         unique_partition(),
                                         "--expect",
                                         "1",
                                         "--timeout",
                                         "1"};
  ChildProcess reader(args);
  const std::string out = reader.read_all(milliseconds(10000));
  const auto code = reader.wait_exit(milliseconds(5000));
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 1) << out;
  EXPECT_EQ(out, "");
}

TEST(LateJoinerTest, PublisherExitsOnSigint) {
  const std::vector<std::string> args = {kProbe,
                                         "publish-faults",
                                         "--profiles",
                                         kProfilesFile,
                                         "--domain",
                                         std::to_string(test_domain_id()),
                                         "--participant-profile",
                                         profiles::kParticipantLoopback,
                                         "--partition",
                                         unique_partition(),
                                         "--vessels",
                                         "1",
                                         "--sensors",
                                         "1",
                                         "--timeout",
                                         "20"};
  ChildProcess publisher(args);
  ASSERT_TRUE(publisher.read_line(milliseconds(10000)).has_value());
  publisher.signal(SIGINT);
  const auto code = publisher.wait_exit(milliseconds(2000));
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 0);
}

}  // namespace
}  // namespace usvfdi::dds::test

namespace usvfdi::dds::test {
namespace {

// A deployment overrides any shipped QoS profile through FASTRTPS_DEFAULT_PROFILES_FILE,
// without editing config/qos/usv_fdi_profiles.xml: that file is loaded first and its
// profiles win for the same name. Checked in a child process (the default profiles are loaded
// once per process).
TEST(XmlProfiles, DefaultProfilesFileOverridesAShippedProfile) {
  const std::string override_xml =
      ::testing::TempDir() + "usv_fdi_override_" + std::to_string(::getpid()) + ".xml";
  {
    std::ofstream f(override_xml);
    f << R"(<?xml version="1.0" encoding="UTF-8" ?>
<dds xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <profiles>
    <data_writer profile_name="usv_fdi_status_writer">
      <topic>
        <historyQos><kind>KEEP_LAST</kind><depth>3</depth></historyQos>
        <resourceLimitsQos>
          <max_samples>300</max_samples>
          <max_instances>100</max_instances>
          <max_samples_per_instance>3</max_samples_per_instance>
        </resourceLimitsQos>
      </topic>
      <qos><durability><kind>VOLATILE</kind></durability></qos>
    </data_writer>
  </profiles>
</dds>)";
  }
  auto qos_of = [&](const std::vector<std::string>& env) {
    ChildProcess p({kProbe, "writer-qos", "--profiles", kProfilesFile, "--domain",
                    std::to_string(test_domain_id()), "--participant-profile",
                    profiles::kParticipantLoopback, "--writer-profile", profiles::kStatusWriter},
                   "", env);
    const std::string out = p.read_all(std::chrono::milliseconds(10000));
    EXPECT_EQ(p.wait_exit(std::chrono::milliseconds(5000)).value_or(-1), 0) << out;
    return out;
  };
  // Shipped: TRANSIENT_LOCAL (1), KEEP_LAST 1, 4096 instances.
  EXPECT_EQ(qos_of({}), "reliability=2 durability=1 depth=1 max_instances=4096\n");
  // (Fast DDS also logs "Error adding profile 'usv_fdi_status_writer'" when our file repeats
  // the name: expected, the first definition stays.)
  const std::string overridden = qos_of({"FASTRTPS_DEFAULT_PROFILES_FILE=" + override_xml});
  EXPECT_NE(overridden.find("reliability=2 durability=0 depth=3 max_instances=100\n"),
            std::string::npos)
      << overridden;
  std::remove(override_xml.c_str());
}

}  // namespace
}  // namespace usvfdi::dds::test
