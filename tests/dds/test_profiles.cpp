// The shipped XML profiles load without any Fast DDS error, resolve to the intended QoS, and
// every writer/reader profile yields a consistent endpoint; DdsContext reports failures by name.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>

#include "test_env.hpp"
#include "usv_fdi/dds/dds_context.hpp"

namespace usvfdi::dds::test {
namespace {

namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

// Collects Fast DDS error log entries (the XML parser reports problems only through the log).
class ErrorCollector : public fdds::LogConsumer {
 public:
  void Consume(const fdds::Log::Entry& entry) override {
    if (entry.kind != fdds::Log::Kind::Error) return;
    std::lock_guard<std::mutex> lock(mutex());
    errors().push_back(std::string(entry.context.category ? entry.context.category : "") + ": " +
                       entry.message);
  }
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static std::vector<std::string>& errors() {
    static std::vector<std::string> e;
    return e;
  }
  static std::vector<std::string> take() {
    fdds::Log::Flush();
    std::lock_guard<std::mutex> lock(mutex());
    std::vector<std::string> out;
    out.swap(errors());
    return out;
  }
  static void install() {
    static std::once_flag once;
    std::call_once(once, [] { fdds::Log::RegisterConsumer(std::make_unique<ErrorCollector>()); });
  }
};

std::string join(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += l + "\n";
  return out;
}

std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path =
      ::testing::TempDir() + "usv_fdi_" + std::to_string(::getpid()) + "_" + name + ".xml";
  std::ofstream(path) << text;
  return path;
}

DdsConfig test_config() {
  DdsConfig c;
  c.profiles_file = kProfilesFile;
  c.domain_id = test_domain_id();
  c.participant_profile = profiles::kParticipantLoopback;
  const std::string partition = unique_partition();
  c.publisher_partitions = {partition};
  c.subscriber_partitions = {partition};
  return c;
}

TEST(XmlProfiles, ShippedFileLoadsWithoutErrors) {
  ErrorCollector::install();
  ErrorCollector::take();
  // Directly through Fast DDS first (the return code), then through our idempotent wrapper.
  EXPECT_EQ(fdds::DomainParticipantFactory::get_instance()->load_XML_profiles_file(kProfilesFile),
            ReturnCode_t::RETCODE_OK);
  EXPECT_NO_THROW(load_profiles_file(kProfilesFile));
  EXPECT_NO_THROW(load_profiles_file(kProfilesFile));  // second load is a no-op
  const auto errors = ErrorCollector::take();
  EXPECT_TRUE(errors.empty()) << join(errors);
}

TEST(XmlProfiles, MalformedXmlIsRejected) {
  ErrorCollector::install();
  const std::string path = write_temp("malformed", "<dds><profiles><participant profile_name=");
  EXPECT_THROW(load_profiles_file(path), std::runtime_error);
  EXPECT_FALSE(ErrorCollector::take().empty());
}

TEST(XmlProfiles, UnknownQosElementIsRejected) {
  ErrorCollector::install();
  const std::string path = write_temp("unknown_element", R"(<?xml version="1.0" encoding="UTF-8" ?>
<dds xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <profiles>
    <data_writer profile_name="usv_fdi_test_bad_writer">
      <qos><reliability><kind>RELIABEL</kind></reliability></qos>
    </data_writer>
  </profiles>
</dds>)");
  EXPECT_THROW(load_profiles_file(path), std::runtime_error);
  EXPECT_FALSE(ErrorCollector::take().empty());
}

/// The message load_profiles_file throws for path ("" if it does not throw).
std::string load_error(const std::string& path) {
  try {
    load_profiles_file(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(XmlProfiles, MissingFileIsRejected) {
  EXPECT_THROW(load_profiles_file("/nonexistent/usv_fdi_profiles.xml"), std::runtime_error);
}

TEST(XmlProfiles, AnUnreadableFileIsRejectedWithTheSystemsReason) {
  // The reasons of open(2), each provoked whatever the user (root ignores mode bits).
  const std::string file = write_temp("plain", "not a directory");
  struct Case {
    std::string path, reason;
  };
  const Case cases[] = {
      {"/nonexistent/usv_fdi_profiles.xml", "No such file or directory"},
      {file + "/profiles.xml", "Not a directory"},
      {::testing::TempDir(), "Is a directory"},
  };
  for (const Case& c : cases) {
    const std::string what = load_error(c.path);
    EXPECT_NE(what.find("cannot read the XML profiles file '" + c.path + "': " + c.reason),
              std::string::npos)
        << what;
  }
}

TEST(XmlProfiles, FaultEventQosIsAsSpecified) {
  DdsContext ctx(test_config());
  for (const char* name : {profiles::kFaultEventWriter, profiles::kStatusWriter}) {
    fdds::DataWriterQos w;
    ASSERT_EQ(ctx.publisher().get_datawriter_qos_from_profile(name, w), ReturnCode_t::RETCODE_OK)
        << name;
    EXPECT_EQ(w.reliability().kind, fdds::RELIABLE_RELIABILITY_QOS) << name;
    EXPECT_EQ(w.durability().kind, fdds::TRANSIENT_LOCAL_DURABILITY_QOS) << name;
    EXPECT_EQ(w.history().kind, fdds::KEEP_LAST_HISTORY_QOS) << name;
    EXPECT_EQ(w.history().depth, 1) << name;
    EXPECT_EQ(w.resource_limits().max_instances, 4096) << name;
    EXPECT_EQ(w.resource_limits().max_samples_per_instance, 1) << name;
    EXPECT_EQ(w.resource_limits().max_samples, 4096) << name;
  }
  // A late joiner learns of the latched samples from the writer's heartbeat: Fast DDS's
  // default period of 3 s made late joins of the monitor (and of other vendors' readers)
  // wait up to 3 s. Acknowledgements are repaired as fast.
  // The same for usv-fdi ros2's writers: its keyless mirrors are latched too.
  for (const char* name : {profiles::kFaultEventWriter, profiles::kStatusWriter,
                           profiles::kFaultAckWriter, "usv_fdi_ros2_fault_event_writer",
                           "usv_fdi_ros2_status_writer", "usv_fdi_ros2_diagnostics_writer"}) {
    fdds::DataWriterQos w;
    ASSERT_EQ(ctx.publisher().get_datawriter_qos_from_profile(name, w), ReturnCode_t::RETCODE_OK)
        << name;
    const auto& hb = w.reliable_writer_qos().times.heartbeatPeriod;
    EXPECT_LE(hb.to_ns(), 100'000'000)
        << name << ": heartbeat period " << hb.seconds << " s " << hb.nanosec << " ns";
  }
  for (const char* name : {profiles::kFaultEventReader, profiles::kStatusReader}) {
    fdds::DataReaderQos r;
    ASSERT_EQ(ctx.subscriber().get_datareader_qos_from_profile(name, r), ReturnCode_t::RETCODE_OK)
        << name;
    EXPECT_EQ(r.reliability().kind, fdds::RELIABLE_RELIABILITY_QOS) << name;
    EXPECT_EQ(r.durability().kind, fdds::TRANSIENT_LOCAL_DURABILITY_QOS) << name;
    EXPECT_EQ(r.history().kind, fdds::KEEP_LAST_HISTORY_QOS) << name;
    EXPECT_EQ(r.resource_limits().max_instances, 4096) << name;
    // Fault events: room for the owner's and other writers' samples of one instance, so a
    // late joiner that receives them at once keeps the owner's (InstanceOwners picks it).
    const int per_instance = name == std::string(profiles::kFaultEventReader) ? 16 : 1;
    EXPECT_EQ(r.history().depth, per_instance) << name;
    EXPECT_EQ(r.resource_limits().max_samples_per_instance, per_instance) << name;
  }
  fdds::DataReaderQos ack;
  ASSERT_EQ(ctx.subscriber().get_datareader_qos_from_profile(profiles::kFaultAckReader, ack),
            ReturnCode_t::RETCODE_OK);
  EXPECT_EQ(ack.reliability().kind, fdds::RELIABLE_RELIABILITY_QOS);
  EXPECT_EQ(ack.durability().kind, fdds::VOLATILE_DURABILITY_QOS);
  EXPECT_EQ(ack.history().depth, 64);
  fdds::DataReaderQos ins;
  ASSERT_EQ(ctx.subscriber().get_datareader_qos_from_profile(profiles::kInsReaderBestEffort, ins),
            ReturnCode_t::RETCODE_OK);
  EXPECT_EQ(ins.reliability().kind, fdds::BEST_EFFORT_RELIABILITY_QOS);
  EXPECT_EQ(ins.history().depth, 32);
  EXPECT_EQ(ins.resource_limits().max_instances, 4096);
}

TEST(XmlProfiles, EveryParticipantProfileResolves) {
  load_profiles_file(kProfilesFile);
  auto* factory = fdds::DomainParticipantFactory::get_instance();
  for (const char* name :
       {profiles::kParticipant, profiles::kParticipantLoopback, profiles::kParticipantShm}) {
    fdds::DomainParticipantQos qos;
    EXPECT_EQ(factory->get_participant_qos_from_profile(name, qos), ReturnCode_t::RETCODE_OK)
        << name;
  }
  // Creating one is only done for the host-local profiles (the builtin one would announce itself
  // by multicast on every interface).
  DdsConfig c = test_config();
  c.participant_profile = profiles::kParticipantShm;
  EXPECT_NO_THROW(DdsContext{c});
}

// A participant whose answer to a late joiner's first announcements goes astray is found at
// its next periodic announcement: Fast DDS's default period of 3 s made about one late join in
// five (a monitor's, a dashboard's) wait ~3 s (usv_fdi_bench_dds, part 3).
TEST(XmlProfiles, HostLocalParticipantsAnnounceThemselvesEverySecond) {
  load_profiles_file(kProfilesFile);
  auto* factory = fdds::DomainParticipantFactory::get_instance();
  for (const char* name : {profiles::kParticipantLoopback, profiles::kParticipantShm}) {
    fdds::DomainParticipantQos qos;
    ASSERT_EQ(factory->get_participant_qos_from_profile(name, qos), ReturnCode_t::RETCODE_OK)
        << name;
    const auto& d = qos.wire_protocol().builtin.discovery_config;
    EXPECT_LE(d.leaseDuration_announcementperiod.to_ns(), 1'000'000'000) << name;
    // The lease must stay well above the period: three missed announcements are not a loss.
    EXPECT_GE(d.leaseDuration.to_ns(), 5 * d.leaseDuration_announcementperiod.to_ns()) << name;
  }
}

TEST(XmlProfiles, EveryProfileCreatesAnEndpoint) {
  ErrorCollector::install();
  ErrorCollector::take();
  DdsContext ctx(test_config());
  struct Pair {
    TopicId topic;
    const char* writer;
    const char* reader;
  };
  const Pair pairs[] = {
      {TopicId::kIns, profiles::kInsWriterBestEffort, profiles::kInsReaderBestEffort},
      {TopicId::kIns, profiles::kInsWriterReliable, profiles::kInsReaderReliable},
      {TopicId::kRudder, profiles::kRudderWriterBestEffort, profiles::kRudderReaderBestEffort},
      {TopicId::kRudder, profiles::kRudderWriterReliable, profiles::kRudderReaderReliable},
      {TopicId::kFaultEvent, profiles::kFaultEventWriter, profiles::kFaultEventReader},
      {TopicId::kFaultAck, profiles::kFaultAckWriter, profiles::kFaultAckReader},
      {TopicId::kStatus, profiles::kStatusWriter, profiles::kStatusReader},
  };
  for (const auto& p : pairs) {
    fdds::DataWriter* w = nullptr;
    fdds::DataReader* r = nullptr;
    EXPECT_NO_THROW(w = &ctx.create_writer(p.topic, p.writer)) << p.writer;
    EXPECT_NO_THROW(r = &ctx.create_reader(p.topic, p.reader)) << p.reader;
    if (w != nullptr) {
      EXPECT_NO_THROW(ctx.delete_writer(*w));
    }
    if (r != nullptr) {
      EXPECT_NO_THROW(ctx.delete_reader(*r));
    }
  }
  const auto errors = ErrorCollector::take();
  EXPECT_TRUE(errors.empty()) << join(errors);
}

TEST(DdsContext, TwoContextsOfOneProcessAreDeletedWithoutACrash) {
  // The sidecar's shape: one participant with the INS, rudder and fault-event endpoints, a
  // second one of its own for the acks, deleted ack participant first while discovery
  // between the two may still be under way. With Fast DDS's intraprocess delivery the
  // first participant's discovery writer could then hand a gap to the deleted
  // participant's reader (a crash in StatefulWriter::intraprocess_gap, a few times in a
  // hundred sidecar stops on a loaded machine); DdsContext sends discovery between
  // participants of one process over the transports.
  for (int i = 0; i < 40; ++i) {
    SCOPED_TRACE(i);
    const DdsConfig c = test_config();
    auto main = std::make_unique<DdsContext>(c);
    main->create_reader(TopicId::kIns, profiles::kInsReaderReliable);
    main->create_reader(TopicId::kRudder, profiles::kRudderReaderReliable);
    main->create_writer(TopicId::kFaultEvent, profiles::kFaultEventWriter);
    main->create_reader(TopicId::kFaultEvent, profiles::kFaultEventReader);
    auto acks = std::make_unique<DdsContext>(c);
    acks->create_reader(TopicId::kFaultAck, profiles::kFaultAckReader);
    std::this_thread::sleep_for(std::chrono::milliseconds(i % 8));
    acks.reset();
    main.reset();
  }
}

TEST(DdsContext, FailuresNameWhatFailed) {
  DdsConfig bad = test_config();
  bad.participant_profile = "no_such_participant_profile";
  try {
    DdsContext ctx(bad);
    ADD_FAILURE() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_participant_profile"), std::string::npos)
        << e.what();
  }

  DdsContext ctx(test_config());
  try {
    ctx.create_writer(TopicId::kFaultEvent, "no_such_writer_profile");
    ADD_FAILURE() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_writer_profile"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ctx.create_reader(TopicId::kStatus, "no_such_reader_profile"), std::runtime_error);
}

TEST(DdsContext, TopicsUseConfiguredNames) {
  DdsConfig c = test_config();
  c.topics.fault_event = "custom/fault_event";
  DdsContext ctx(c);
  EXPECT_EQ(ctx.topic(TopicId::kFaultEvent).get_name(), "custom/fault_event");
  EXPECT_EQ(ctx.topic(TopicId::kFaultEvent).get_type_name(), "fdi::FaultEvent");
  EXPECT_EQ(ctx.topic(TopicId::kIns).get_name(), c.topics.ins);
  EXPECT_EQ(ctx.topic(TopicId::kStatus).get_type_name(), "fdi::FdiStatus");
}

TEST(DdsContext, InProcessStatusRoundTrip) {
  DdsContext ctx(test_config());
  fdds::DataReader& reader = ctx.create_reader<fdi::FdiStatus>(profiles::kStatusReader);
  fdds::DataWriter& writer = ctx.create_writer<fdi::FdiStatus>(profiles::kStatusWriter);

  fdi::FdiStatus status;
  status.mmsi(257123456);
  status.stamp(42.5);
  status.a({0.9, 0.1, -0.2, 0.8});
  status.converged(true);
  status.poles_v({-0.5, -0.6});
  status.samples(1000);
  status.message("ok");
  write(writer, status);

  fdds::StatusCondition& cond = reader.get_statuscondition();
  cond.set_enabled_statuses(fdds::StatusMask::data_available());
  fdds::WaitSet ws;
  ws.attach_condition(cond);
  std::vector<fdi::FdiStatus> got;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (got.empty() && std::chrono::steady_clock::now() < deadline) {
    fdds::ConditionSeq active;
    (void)ws.wait(active, eprosima::fastrtps::Duration_t(0, 100000000));
    take_all(reader, got);
  }
  ws.detach_condition(cond);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], status);
}

}  // namespace
}  // namespace usvfdi::dds::test
