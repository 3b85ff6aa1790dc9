// The sidecar's YAML (engine keys + `service:` section): the shipped example loads with the
// documented values; every mistake is an error naming file, line, key and value.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "usv_fdi/dds_service/service.hpp"
#include "usv_fdi/io/config.hpp"

namespace usvfdi::dds_service {
namespace {

const std::string kSource = USV_FDI_SOURCE_DIR;

std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path =
      ::testing::TempDir() + "usv_fdi_svc_" + std::to_string(::getpid()) + "_" + name + ".yaml";
  std::ofstream f(path);
  f << text;
  return path;
}

TEST(ServiceConfig, ShippedExampleLoadsWithItsDocumentedValues) {
  const ServiceConfig c = load_service_config(kSource + "/config/service/example.yaml");
  EXPECT_EQ(c.mmsi, 257000001u);
  EXPECT_EQ(c.dds.domain_id, 0u);
  EXPECT_EQ(c.dds.participant_profile, "usv_fdi_participant");
  EXPECT_EQ(c.dds.topics.fault_event, "usv_fdi/fault_event");
  EXPECT_EQ(c.dds.topics.speed, "usv_fdi/speed");
  EXPECT_DOUBLE_EQ(c.pipeline.speed_max_age, 2.0);
  EXPECT_TRUE(c.dds.publisher_partitions.empty());
  EXPECT_FALSE(c.reliable_inputs);
  EXPECT_DOUBLE_EQ(c.pipeline.status_period, 1.0);
  EXPECT_EQ(c.pipeline.input_capacity, 4096u);
  EXPECT_EQ(c.log_level, "info");
  // qos_profiles is relative to the config file.
  EXPECT_EQ(c.dds.profiles_file, kSource + "/config/qos/usv_fdi_profiles.xml");
  EXPECT_DOUBLE_EQ(c.engine.B(0), 0.165394);
  // Latched faults are kept in the default state directory (if it exists); no health file.
  EXPECT_EQ(c.state_dir, "/var/lib/usv-fdi");
  EXPECT_FALSE(c.state_dir_explicit);
  EXPECT_EQ(c.health_file, "");
  EXPECT_EQ(c.metrics, "");  // no Prometheus endpoint unless asked
  EXPECT_DOUBLE_EQ(c.pipeline.restore_recheck, 5.0);
  // Statuses are event-triggered, with a heartbeat.
  EXPECT_TRUE(c.uplink.event);
  EXPECT_DOUBLE_EQ(c.uplink.heartbeat, 3.0);
}

TEST(ServiceConfig, EveryServiceKeyIsApplied) {
  const std::string path = write_temp("all", R"(model:
  B: [0.1, -2.0]
service:
  mmsi: 123456789
  domain_id: 42
  participant_profile: usv_fdi_participant_shm
  topics: {ins: a/ins, rudder: a/rudder, fault_event: a/ev, fault_ack: a/ack, status: a/st}
  partitions: [fleet_a, fleet_b]
  reliable_inputs: true
  status_rate: 4
  log_level: debug
  authorised_operators: [alice, bob]
  input_queue: 100
  rudder_wait: 0.2
  rudder_timeout: 0.7
  input_timeout: 3
  restore_recheck: 8
  state_dir: state
  health_file: /run/usv-fdi/health.json
  metrics: 0.0.0.0:9464
  status_uplink: {mode: periodic, heartbeat: 2, tolerance: 0.05, theta: 3, decay: 0.5}
)");
  const ServiceConfig c = load_service_config(path);
  EXPECT_FALSE(c.uplink.event);
  EXPECT_DOUBLE_EQ(c.uplink.heartbeat, 2.0);
  EXPECT_DOUBLE_EQ(c.uplink.tolerance, 0.05);
  EXPECT_DOUBLE_EQ(c.uplink.theta, 3.0);
  EXPECT_DOUBLE_EQ(c.uplink.decay, 0.5);
  EXPECT_EQ(c.mmsi, 123456789u);
  EXPECT_EQ(c.dds.domain_id, 42u);
  EXPECT_EQ(c.dds.participant_profile, "usv_fdi_participant_shm");
  EXPECT_EQ(c.dds.topics.ins, "a/ins");
  EXPECT_EQ(c.dds.topics.rudder, "a/rudder");
  EXPECT_EQ(c.dds.topics.fault_event, "a/ev");
  EXPECT_EQ(c.dds.topics.fault_ack, "a/ack");
  EXPECT_EQ(c.dds.topics.status, "a/st");
  EXPECT_EQ(c.dds.publisher_partitions, (std::vector<std::string>{"fleet_a", "fleet_b"}));
  EXPECT_EQ(c.dds.subscriber_partitions, c.dds.publisher_partitions);
  EXPECT_TRUE(c.reliable_inputs);
  EXPECT_DOUBLE_EQ(c.pipeline.status_period, 0.25);
  EXPECT_EQ(c.log_level, "debug");
  EXPECT_EQ(c.pipeline.authorised_operators, (std::vector<std::string>{"alice", "bob"}));
  EXPECT_EQ(c.pipeline.input_capacity, 100u);
  EXPECT_DOUBLE_EQ(c.pipeline.rudder_wait, 0.2);
  EXPECT_DOUBLE_EQ(c.pipeline.rudder_timeout, 0.7);
  EXPECT_DOUBLE_EQ(c.pipeline.input_timeout, 3.0);
  EXPECT_DOUBLE_EQ(c.pipeline.restore_recheck, 8.0);
  // Relative to the config file.
  EXPECT_EQ(c.state_dir, (std::filesystem::path(path).parent_path() / "state").string());
  EXPECT_TRUE(c.state_dir_explicit);
  EXPECT_EQ(c.health_file, "/run/usv-fdi/health.json");
  EXPECT_EQ(c.metrics, "0.0.0.0:9464");
  std::remove(path.c_str());
  // An empty state_dir switches persistence off.
  const std::string off =
      write_temp("off", "model:\n  B: [0.1, -2.0]\nservice:\n  state_dir: \"\"\n");
  const ServiceConfig o = load_service_config(off);
  EXPECT_EQ(o.state_dir, "");
  EXPECT_TRUE(o.state_dir_explicit);
  std::remove(off.c_str());
}

TEST(ServiceConfig, MistakesNameFileLineKeyAndValue) {
  struct Case {
    std::string service;  // lines of the service section
    std::string expect;   // in the message, after "<file>:"
  };
  const Case cases[] = {
      {"  mmsi: 0", "4: service.mmsi = 0: must be an MMSI"},
      {"  mmsi: 1000000000", "4: service.mmsi = 1000000000: must be an MMSI"},
      {"  domain_id: 233", "4: service.domain_id = 233: must be 0..232"},
      {"  domain_id: x", "4: service.domain_id = x: must be an integer"},
      {"  status_rate: 0", "4: service.status_rate = 0: must be a positive rate"},
      {"  status_uplink: {mode: sometimes}",
       "4: service.status_uplink.mode = sometimes: must be event"},
      {"  status_uplink: {heartbeat: 0}", "4: service.status_uplink.heartbeat = 0: must be"},
      {"  status_uplink: {decay: 1}", "4: service.status_uplink.decay = 1: must be"},
      {"  status_uplink: {burst: 1}", "4: service.status_uplink.burst"},
      {"  log_level: loud", "4: service.log_level = loud: must be one of"},
      {"  partitions: fleet", "4: service.partitions = fleet: must be a list"},
      {"  topics: {ins: a, radar: b}", "4: service.topics.radar = b: unknown topic"},
      {"  topics: {ins: a, status: a}",
       "4: service.topics.status = a: the same topic name as service.topics.ins"},
      {"  topics: {fault_ack: usv_fdi/status}",
       "4: service.topics.fault_ack = usv_fdi/status: the same topic name as "
       "service.topics.status"},
      {"  input_queue: 0", "4: service.input_queue = 0: must be 1..1000000"},
      {"  rudder_wait: -1", "4: service.rudder_wait = -1: must be a positive time"},
      {"  reliable_inputs: maybe", "4: service.reliable_inputs = maybe: must be true or false"},
      {"  qos_profiles: missing.xml", "4: service.qos_profiles = missing.xml: no such file"},
      {"  qos_profiles: " + kSource + "/README.md/qos.xml",
       "4: service.qos_profiles = " + kSource + "/README.md/qos.xml: cannot read " + kSource +
           "/README.md/qos.xml: Not a directory"},
      {"  qos_profiles: " + kSource + "/config", "4: service.qos_profiles = " + kSource +
                                                     "/config: cannot read " + kSource +
                                                     "/config: Is a directory"},
      {"  mmsi: 1\n  colour: red", "5: service.colour = colour: unknown key"},
      {"  input_timeout: 0.2",
       "4: service.input_timeout = 0.2: must be at least isolation.stale_timeout (0.5 s)"},
      {"  restore_recheck: 0", "4: service.restore_recheck = 0: must be a positive time"},
      {"  state_dir: [a]", "4: service.state_dir = <list>: must be a directory"},
      {"  state_dir: " + kSource + "/README.md",
       "4: service.state_dir = " + kSource + "/README.md: not a directory"},
      {"  health_file: {a: 1}", "4: service.health_file = <mapping>: must be a file path"},
      {"  metrics: 9464", "4: service.metrics = 9464: must be HOST:PORT"},
      {"  metrics: 127.0.0.1:99999", "4: service.metrics = 127.0.0.1:99999: must be HOST:PORT"},
      {"  metrics: '127.0.0.1:9464,0.0.0.0:1'",
       "4: service.metrics = 127.0.0.1:9464,0.0.0.0:1: must be HOST:PORT"},
  };
  for (const Case& c : cases) {
    const std::string path =
        write_temp("bad", "model:\n  B: [0.1, -2.0]\nservice:\n" + c.service + "\n");
    try {
      load_service_config(path);
      ADD_FAILURE() << "accepted: " << c.service;
    } catch (const io::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(path + ":" + c.expect), std::string::npos)
          << e.what() << "\n  expected: " << c.expect;
    }
    std::remove(path.c_str());
  }
  // The section must be a mapping; engine mistakes are reported by the engine loader.
  const std::string p1 = write_temp("list", "model:\n  B: [0.1, -2.0]\nservice: [1, 2]\n");
  EXPECT_THROW(load_service_config(p1), io::ConfigError);
  const std::string p2 = write_temp("engine", "model:\n  B: [0.1]\nservice:\n  mmsi: 1\n");
  EXPECT_THROW(load_service_config(p2), io::ConfigError);
  std::remove(p1.c_str());
  std::remove(p2.c_str());
}

TEST(ServiceConfig, NmeaInputKeys) {
  // GIVEN the default (DDS inputs) and a config with every key of the NMEA input
  const ServiceConfig d = load_service_config(kSource + "/config/service/example.yaml");
  EXPECT_EQ(d.input, InputSource::kDds);
  EXPECT_EQ(d.nmea.endpoint.address, "239.192.0.1");
  EXPECT_EQ(d.nmea.endpoint.port, 60001);
  const std::string path = write_temp("nmea", R"(model:
  B: [0.1, 2.0]
service:
  input: nmea
  nmea:
    address: 239.192.0.4
    port: 60004
    interface: 127.0.0.1
    rate: 20
    max_age: 0.5
    hold_until_due: true
    receive_buffer: 65536
)");
  // THEN each is applied, and the rudder sign follows model.B (b2 > 0: RSA's sign)
  const ServiceConfig c = load_service_config(path);
  EXPECT_EQ(c.input, InputSource::kNmea);
  EXPECT_EQ(c.nmea.endpoint.address, "239.192.0.4");
  EXPECT_EQ(c.nmea.endpoint.port, 60004);
  EXPECT_EQ(c.nmea.interface_address, "127.0.0.1");
  EXPECT_DOUBLE_EQ(c.nmea.assembler.rate_hz, 20.0);
  EXPECT_DOUBLE_EQ(c.nmea.assembler.max_age_s, 0.5);
  EXPECT_TRUE(c.nmea.assembler.hold_until_due);
  EXPECT_FALSE(d.nmea.assembler.hold_until_due);
  EXPECT_EQ(c.nmea.receive_buffer, 65536);
  EXPECT_EQ(c.nmea.assembler.rudder_sign, nmea::RudderSign::kPositiveToStarboard);
  EXPECT_EQ(d.nmea.assembler.rudder_sign, nmea::RudderSign::kPositiveToPort);  // b2 < 0
  std::remove(path.c_str());
  // AND mistakes name the file, line and key
  const std::pair<std::string, std::string> cases[] = {
      {"  input: serial", "4: service.input = serial: must be dds"},
      {"  nmea:\n    address: vessel", "5: service.nmea.address = vessel: "},
      {"  nmea:\n    port: 70000", "5: service.nmea.port = 70000: must be a UDP port"},
      {"  nmea:\n    rate: 0", "5: service.nmea.rate = 0: must be 0.001 to 10000 Hz"},
      {"  nmea:\n    hold_until_due: sometimes", "5: service.nmea.hold_until_due = sometimes: "},
      {"  nmea:\n    group: 239.192.0.1", "5: service.nmea.group = group: unknown key"},
  };
  for (const auto& [service, expect] : cases) {
    const std::string bad =
        write_temp("bad", "model:\n  B: [0.1, -2.0]\nservice:\n" + service + "\n");
    try {
      load_service_config(bad);
      ADD_FAILURE() << "accepted: " << service;
    } catch (const io::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(bad + ":" + expect), std::string::npos)
          << e.what() << "\n  expected: " << expect;
    }
    std::remove(bad.c_str());
  }
}

}  // namespace
}  // namespace usvfdi::dds_service
