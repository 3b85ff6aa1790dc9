// usv_fdi_secure_probe: helper process for the DDS Security tests (issue 4). Like
// tests/dds/probe.cpp, but every participant may load DDS Security participant profiles (made by
// scripts/make-security.sh) and it reports which entities Fast DDS refused.
//
// Common options:
//   --qos FILE                 usv-fdi QoS profiles (config/qos/usv_fdi_profiles.xml), required
//   --security FILE            security participant profiles, loaded first (optional: without it
//                              the participant is a plain, unauthenticated one)
//   --participant-profile P    participant profile name (in FILE or in the QoS profiles)
//   --domain N  --partition X  --timeout SECONDS
//
//   usv_fdi_secure_probe sidecar ... [--mmsi M] [--sensors S]
//     Stands in for a vessel's sidecar: writes one latched FaultEvent per sensor (mmsi M, state
//     RAISED, sequence 1), reads INS samples and FaultAcks and prints one line per sample as it
//     arrives:  ins mmsi=.. seq=..   |   ack mmsi=.. sensor=.. sequence=.. operator=..
//     Prints "ready" once its events are written. Runs until SIGTERM/SIGINT (exit 0) or the
//     timeout (exit 2).
//
//   usv_fdi_secure_probe peer ... [--read-faults 0|1] [--write-ins 0|1] [--write-acks 0|1]
//       [--mmsi M] [--operator NAME] [--duration SECONDS] [--until-faults K]
//     A fleet participant: for --duration seconds (or until SIGTERM/SIGINT, or, with
//     --until-faults K, until 2 s after K event instances arrived) reads FaultEvents and/or writes
//     one INS sample (mmsi M) and one FaultAck (operator NAME, acknowledging mmsi M sensor 0
//     sequence 1) every 100 ms. Prints, for each entity asked for, "<entity> created" or "<entity>
//     refused: <why>" (entity: fault_reader, ins_writer, ack_writer), then at the end
//       fault instance mmsi=.. sensor=.. sequence=.. message=..    (one per instance received)
//       summary faults=<instances> ins_written=<n> acks_written=<n> first_fault_ms=<ms or -1>
//     and exits 0.
//
// Exit code 3: usage error; 4: DDS error (e.g. the participant itself was refused).
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/core/status/StatusMask.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/log/StdoutErrConsumer.hpp>

#include "probe_common.hpp"
#include "usv_fdi/dds/dds_context.hpp"
#include "usv_fdi/dds/profiles.hpp"

namespace {

namespace fdds = eprosima::fastdds::dds;
using usvfdi::dds::DdsConfig;
using usvfdi::dds::DdsContext;
namespace profiles = usvfdi::dds::profiles;
using Clock = std::chrono::steady_clock;
using usvfdi::test_support::probe::deadline_after;
using usvfdi::test_support::probe::g_stop;
using usvfdi::test_support::probe::install_signal_handlers;
using usvfdi::test_support::probe::parse_unsigned;
using usvfdi::test_support::probe::UsageError;

struct Options {
  std::string mode;
  DdsConfig dds;
  std::string security_file;
  std::uint32_t mmsi = 257000000;
  unsigned sensors = 2;
  bool read_faults = false;
  bool write_ins = false;
  bool write_acks = false;
  std::string operator_id = "probe";
  double duration_s = 5.0;
  unsigned until_faults = 0;
  double timeout_s = 30.0;
};

double parse_seconds(const std::string& flag, const std::string& value) {
  try {
    std::size_t used = 0;
    const double v = std::stod(value, &used);
    if (used != value.size() || !(v > 0.0) || v > 3600.0) throw std::invalid_argument(value);
    return v;
  } catch (const std::exception&) {
    throw UsageError(flag + ": expected seconds in (0, 3600]: '" + value + "'");
  }
}

bool parse_flag(const std::string& flag, const std::string& value) {
  if (value == "0") return false;
  if (value == "1") return true;
  throw UsageError(flag + ": expected 0 or 1: '" + value + "'");
}

Options parse(int argc, char** argv) {
  if (argc < 2) throw UsageError("missing mode (sidecar | peer)");
  Options o;
  o.mode = argv[1];
  if (o.mode != "sidecar" && o.mode != "peer") throw UsageError("unknown mode '" + o.mode + "'");
  for (int i = 2; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) throw UsageError(flag + ": missing value");
    const std::string value = argv[++i];
    if (flag == "--qos") {
      o.dds.profiles_file = value;
    } else if (flag == "--security") {
      o.security_file = value;
    } else if (flag == "--participant-profile") {
      o.dds.participant_profile = value;
    } else if (flag == "--domain") {
      o.dds.domain_id = static_cast<std::uint32_t>(parse_unsigned(flag, value));
    } else if (flag == "--partition") {
      o.dds.publisher_partitions.push_back(value);
      o.dds.subscriber_partitions.push_back(value);
    } else if (flag == "--mmsi") {
      o.mmsi = static_cast<std::uint32_t>(parse_unsigned(flag, value));
    } else if (flag == "--sensors") {
      o.sensors = static_cast<unsigned>(parse_unsigned(flag, value));
      if (o.sensors < 1 || o.sensors > 3) throw UsageError("--sensors must be 1..3");
    } else if (flag == "--read-faults") {
      o.read_faults = parse_flag(flag, value);
    } else if (flag == "--write-ins") {
      o.write_ins = parse_flag(flag, value);
    } else if (flag == "--write-acks") {
      o.write_acks = parse_flag(flag, value);
    } else if (flag == "--operator") {
      o.operator_id = value;
    } else if (flag == "--until-faults") {
      o.until_faults = static_cast<unsigned>(parse_unsigned(flag, value));
    } else if (flag == "--duration") {
      o.duration_s = parse_seconds(flag, value);
    } else if (flag == "--timeout") {
      o.timeout_s = parse_seconds(flag, value);
    } else {
      throw UsageError("unknown option '" + flag + "'");
    }
  }
  if (o.dds.profiles_file.empty()) throw UsageError("--qos is required");
  return o;
}

Clock::time_point after(double seconds) { return deadline_after(seconds); }

void say(const std::string& line) {
  std::printf("%s\n", line.c_str());
  std::fflush(stdout);
}

std::unique_ptr<DdsContext> make_context(const Options& o) {
  // The security profiles go first so that DdsContext finds the participant profile; the QoS
  // profiles it loads next define the writer and reader profiles.
  if (!o.security_file.empty()) usvfdi::dds::load_profiles_file(o.security_file);
  return std::make_unique<DdsContext>(o.dds);
}

int run_sidecar(const Options& o) {
  const auto deadline = after(o.timeout_s);
  auto ctx = make_context(o);
  fdds::DataWriter& events = ctx->create_writer<fdi::FaultEvent>(profiles::kFaultEventWriter);
  fdds::DataReader& ins = ctx->create_reader<fdi::InsSample>(profiles::kInsReaderReliable);
  fdds::DataReader& acks = ctx->create_reader<fdi::FaultAck>(profiles::kFaultAckReader);
  for (unsigned s = 0; s < o.sensors; ++s) {
    fdi::FaultEvent e;
    e.mmsi(o.mmsi);
    e.sensor(static_cast<std::uint8_t>(s));
    e.state(fdi::STATE_RAISED);
    e.kind(fdi::KIND_BIAS);
    e.sequence(1);
    e.message("secret fault of " + std::to_string(o.mmsi) + "/" + std::to_string(s));
    usvfdi::dds::write(events, e);
  }
  say("ready");

  fdds::WaitSet waitset;
  for (fdds::DataReader* r : {&ins, &acks}) {
    r->get_statuscondition().set_enabled_statuses(fdds::StatusMask::data_available());
    waitset.attach_condition(r->get_statuscondition());
  }
  std::vector<fdi::InsSample> ins_batch;
  std::vector<fdi::FaultAck> ack_batch;
  while (!g_stop.load() && Clock::now() < deadline) {
    fdds::ConditionSeq active;
    (void)waitset.wait(active, eprosima::fastrtps::Duration_t(0, 100000000));
    ins_batch.clear();
    ack_batch.clear();
    usvfdi::dds::take_all(ins, ins_batch);
    usvfdi::dds::take_all(acks, ack_batch);
    for (const auto& s : ins_batch) {
      say("ins mmsi=" + std::to_string(s.mmsi()) + " seq=" + std::to_string(s.seq()));
    }
    for (const auto& a : ack_batch) {
      say("ack mmsi=" + std::to_string(a.mmsi()) + " sensor=" + std::to_string(a.sensor()) +
          " sequence=" + std::to_string(a.sequence()) +
          " operator=" + std::string(a.operator_id().c_str()));
    }
  }
  for (fdds::DataReader* r : {&ins, &acks})
    (void)waitset.detach_condition(r->get_statuscondition());
  const bool by_signal = g_stop.load();
  say(std::string("stopping reason=") + (by_signal ? "signal" : "timeout"));
  return by_signal ? 0 : 2;
}

/// Creates an entity, reporting "<what> created" or "<what> refused: <why>".
template <class Make>
auto try_create(const char* what, Make&& make) -> decltype(make()) {
  try {
    auto* entity = make();
    say(std::string(what) + " created");
    return entity;
  } catch (const std::runtime_error& e) {
    say(std::string(what) + " refused: " + e.what());
    return nullptr;
  }
}

int run_peer(const Options& o) {
  auto ctx = make_context(o);
  fdds::DataReader* faults = nullptr;
  fdds::DataWriter* ins = nullptr;
  fdds::DataWriter* acks = nullptr;
  if (o.read_faults) {
    faults = try_create("fault_reader", [&] {
      return &ctx->create_reader<fdi::FaultEvent>(profiles::kFaultEventReader);
    });
  }
  if (o.write_ins) {
    ins = try_create("ins_writer", [&] {
      return &ctx->create_writer<fdi::InsSample>(profiles::kInsWriterReliable);
    });
  }
  if (o.write_acks) {
    acks = try_create("ack_writer", [&] {
      return &ctx->create_writer<fdi::FaultAck>(profiles::kFaultAckWriter);
    });
  }

  std::map<std::pair<std::uint32_t, unsigned>, fdi::FaultEvent> seen;
  std::vector<fdi::FaultEvent> batch;
  unsigned ins_written = 0;
  unsigned acks_written = 0;
  const auto start = Clock::now();
  const auto end = after(o.duration_s);
  long first_fault_ms = -1;  // time to the first event received (authentication + matching)
  auto next_write = Clock::now();
  std::optional<Clock::time_point> done_at;  // --until-faults: when to stop
  while (!g_stop.load() && Clock::now() < end && !(done_at && Clock::now() >= *done_at)) {
    if (Clock::now() >= next_write) {
      next_write += std::chrono::milliseconds(100);
      if (ins != nullptr) {
        fdi::InsSample s;
        s.mmsi(o.mmsi);
        s.seq(ins_written + 1);
        s.stamp(0.1 * ins_written);
        s.v(0.1);
        s.r(0.01);
        s.v_valid(true);
        s.r_valid(true);
        try {
          usvfdi::dds::write(*ins, s);
          ++ins_written;
        } catch (const std::runtime_error&) {  // counted as not written
        }
      }
      if (acks != nullptr) {
        fdi::FaultAck a;
        a.mmsi(o.mmsi);
        a.sensor(0);
        a.sequence(1);
        a.operator_id(o.operator_id);
        a.stamp(0.1 * acks_written);
        try {
          usvfdi::dds::write(*acks, a);
          ++acks_written;
        } catch (const std::runtime_error&) {
        }
      }
    }
    if (faults != nullptr) {
      batch.clear();
      usvfdi::dds::take_all(*faults, batch);
      for (const auto& e : batch) seen[{e.mmsi(), static_cast<unsigned>(e.sensor())}] = e;
      if (o.until_faults > 0 && !done_at && seen.size() >= o.until_faults) {
        done_at = Clock::now() + std::chrono::seconds(2);  // the acks written meanwhile arrive too
      }
      if (first_fault_ms < 0 && !batch.empty()) {
        first_fault_ms = static_cast<long>(
            std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - start).count());
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  for (const auto& [key, e] : seen) {
    say("fault instance mmsi=" + std::to_string(key.first) +
        " sensor=" + std::to_string(key.second) + " sequence=" + std::to_string(e.sequence()) +
        " message=" + std::string(e.message().c_str()));
  }
  say("summary faults=" + std::to_string(seen.size()) + " ins_written=" +
      std::to_string(ins_written) + " acks_written=" + std::to_string(acks_written) +
      " first_fault_ms=" + std::to_string(first_fault_ms));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // stdout carries the protocol lines the tests parse; Fast DDS's own log (which by default
  // writes to stdout from its logging thread, and can leave a line half written when ours is
  // printed) goes to stderr, every kind of it.
  {
    namespace fdds = eprosima::fastdds::dds;
    auto consumer = std::make_unique<fdds::StdoutErrConsumer>();
    consumer->stderr_threshold(fdds::Log::Kind::Info);
    fdds::Log::ClearConsumers();
    fdds::Log::RegisterConsumer(std::move(consumer));
  }
  try {
    const Options o = parse(argc, argv);
    install_signal_handlers();
    return o.mode == "sidecar" ? run_sidecar(o) : run_peer(o);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "usv_fdi_secure_probe: %s\n", e.what());
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "usv_fdi_secure_probe: %s\n", e.what());
    return 4;
  }
}
