// usv_fdi_dds_probe: helper process for the DDS integration tests.
//
//   usv_fdi_dds_probe publish-faults --profiles FILE [--domain N] [--participant-profile P]
//       [--partition NAME] [--vessels M] [--sensors S] [--state X] [--rewrite-state Y]
//       [--mmsi-base B] [--sequence Q] [--sensor K] [--message TEXT] [--timeout SECONDS]
//     Writes one FaultEvent per (vessel, sensor) with the given state and sequence (default 1;
//     --sensor K: sensor K only); with --rewrite-state also rewrites instance (mmsi-base, sensor 0)
//     with state Y (sequence Q+1). A forger, when another participant owns the instances.
//     Prints "published instances=I writes=W" and stays alive until SIGTERM/SIGINT (exit 0) or
//     the timeout (exit 2).
//
//   usv_fdi_dds_probe read-faults --profiles FILE [--domain N] [--participant-profile P]
//       [--partition NAME] --expect K [--timeout SECONDS] [--settle-ms MS]
//     Late-joining reader: waits until K distinct instances were received (then --settle-ms more
//     for stray samples), prints one line per instance
//       instance mmsi=.. sensor=.. state=.. kind=.. sequence=.. samples=.. message=..
//     and exits 0; exits 1 on timeout (after printing what it has).
//
//   usv_fdi_dds_probe publish-inputs --profiles FILE [DDS options] --mmsi M --script FILE
//       [--timeout SECONDS]
//     A scriptable INS/rudder source (RELIABLE writers) for bad-input tests. Waits until a
//     reader matches both writers, runs the script, waits for the readers' acknowledgements,
//     prints "published ins=N rudder=M" and exits 0. Script lines ('#' comments):
//       ins STAMP V R [V_VALID R_VALID]     one INS sample (nan, inf allowed)
//       rudder STAMP DELTA [VALID]          one rudder sample
//       both T0 T1 DT PACE_MS               rudder + INS pairs for t in [T0, T1) step DT,
//                                           PACE_MS wall-clock ms apart (0: as fast as possible)
//       insonly T0 T1 DT PACE_MS            the same, INS only (a silent rudder)
//       sleep MS
//       skip N                              N INS and N rudder sample numbers (seq) left out,
//                                           as if lost on the way
//
//   usv_fdi_dds_probe slow-reader --profiles FILE [DDS options] [--delay-ms D]
//     The slowest subscriber there is: FaultEvent and FdiStatus readers RELIABLE,
//     TRANSIENT_LOCAL, KEEP_ALL with room for 2 samples per instance, whose listener sleeps D ms
//     (default 200) in Fast DDS's receive thread after every sample it takes. Prints "event mmsi=..
//     sensor=.. sequence=.. state=.." per FaultEvent taken; runs until SIGTERM.
//
//   usv_fdi_dds_probe flood-acks --profiles FILE [DDS options] --mmsi M [--timeout SECONDS]
//     An acknowledgement flood: waits for an ack reader, then writes FaultAcks for vessel M as
//     fast as the RELIABLE writer takes them, all of them to be refused (unknown sequences
//     from 1000000 up, an unknown sensor 7, sequence 0), until SIGTERM/SIGINT or the timeout.
//     Prints "flooding" once matched, then "flooded acks=N" and exits 0.
//
//   usv_fdi_dds_probe read-inputs --profiles FILE [DDS options] --mmsi M [--timeout SECONDS]
//     A RELIABLE reader of the rudder samples a sidecar would read (usv_fdi/rudder). Prints
//     "reading" once created, then "rudder stamp=.. delta=.. valid=.." per sample of vessel M,
//     until SIGTERM/SIGINT (exit 0) or the timeout (exit 0).
//
//   usv_fdi_dds_probe writer-qos --profiles FILE --writer-profile NAME
//     Joins the domain as the service does (FASTRTPS_DEFAULT_PROFILES_FILE first, then FILE)
//     and prints the data writer profile's QoS as
//       reliability=R durability=D depth=N max_instances=M
//
// Exit code 3: usage error; 4: DDS error.
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/core/status/StatusMask.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/log/StdoutErrConsumer.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>

#include "probe_common.hpp"
#include "usv_fdi/dds/dds_context.hpp"

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
  unsigned vessels = 3;
  unsigned sensors = 2;
  unsigned state = 1;
  std::optional<unsigned> rewrite_state;
  std::uint64_t sequence = 1;
  std::optional<unsigned> sensor;
  std::optional<std::string> message;
  std::uint32_t mmsi_base = 257000000;
  double timeout_s = 30.0;
  unsigned expect = 0;
  unsigned settle_ms = 300;
  std::string writer_profile;
  std::uint32_t mmsi = 0;
  std::string script;
  unsigned delay_ms = 200;
};

Options parse(int argc, char** argv) {
  if (argc < 2) {
    throw UsageError(
        "missing mode (publish-faults | read-faults | writer-qos | publish-inputs | slow-reader)");
  }
  Options o;
  o.mode = argv[1];
  if (o.mode != "publish-faults" && o.mode != "read-faults" && o.mode != "writer-qos" &&
      o.mode != "publish-inputs" && o.mode != "slow-reader" && o.mode != "flood-acks" &&
      o.mode != "read-inputs") {
    throw UsageError("unknown mode '" + o.mode + "'");
  }
  for (int i = 2; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) throw UsageError(flag + ": missing value");
    const std::string value = argv[++i];
    if (flag == "--profiles") {
      o.dds.profiles_file = value;
    } else if (flag == "--domain") {
      o.dds.domain_id = static_cast<std::uint32_t>(parse_unsigned(flag, value));
    } else if (flag == "--participant-profile") {
      o.dds.participant_profile = value;
    } else if (flag == "--partition") {
      o.dds.publisher_partitions.push_back(value);
      o.dds.subscriber_partitions.push_back(value);
    } else if (flag == "--vessels") {
      o.vessels = static_cast<unsigned>(parse_unsigned(flag, value));
    } else if (flag == "--sensors") {
      o.sensors = static_cast<unsigned>(parse_unsigned(flag, value));
      if (o.sensors < 1 || o.sensors > 3) throw UsageError("--sensors must be 1..3");
    } else if (flag == "--state") {
      o.state = static_cast<unsigned>(parse_unsigned(flag, value));
    } else if (flag == "--sequence") {
      o.sequence = parse_unsigned(flag, value);
    } else if (flag == "--sensor") {
      o.sensor = static_cast<unsigned>(parse_unsigned(flag, value));
    } else if (flag == "--message") {
      o.message = value;
    } else if (flag == "--rewrite-state") {
      o.rewrite_state = static_cast<unsigned>(parse_unsigned(flag, value));
    } else if (flag == "--mmsi-base") {
      o.mmsi_base = static_cast<std::uint32_t>(parse_unsigned(flag, value));
    } else if (flag == "--timeout") {
      try {
        o.timeout_s = std::stod(value);
      } catch (const std::exception&) {
        throw UsageError("--timeout: not a number: '" + value + "'");
      }
    } else if (flag == "--expect") {
      o.expect = static_cast<unsigned>(parse_unsigned(flag, value));
    } else if (flag == "--writer-profile") {
      o.writer_profile = value;
    } else if (flag == "--settle-ms") {
      o.settle_ms = static_cast<unsigned>(parse_unsigned(flag, value));
    } else if (flag == "--mmsi") {
      o.mmsi = static_cast<std::uint32_t>(parse_unsigned(flag, value));
    } else if (flag == "--script") {
      o.script = value;
    } else if (flag == "--delay-ms") {
      o.delay_ms = static_cast<unsigned>(parse_unsigned(flag, value));
    } else {
      throw UsageError("unknown option '" + flag + "'");
    }
  }
  if (o.dds.profiles_file.empty()) throw UsageError("--profiles is required");
  if (o.mode == "read-faults" && o.expect == 0) throw UsageError("--expect must be > 0");
  return o;
}

fdi::FaultEvent make_event(std::uint32_t mmsi, unsigned sensor, unsigned state,
                           std::uint64_t sequence) {
  fdi::FaultEvent e;
  e.mmsi(mmsi);
  e.sensor(static_cast<std::uint8_t>(sensor));
  e.state(static_cast<std::uint8_t>(state));
  e.kind(fdi::KIND_BIAS);
  e.c_a(0.1 * sensor);
  e.c_g(0.2 * sensor);
  e.statistic(12.5);
  e.threshold(10.0);
  e.onset_time(100.0);
  e.detection_time(101.5);
  e.sequence(sequence);
  e.a({1.0, 0.0, 0.0, 1.0});
  e.message("probe " + std::to_string(mmsi) + "/" + std::to_string(sensor) + " seq " +
            std::to_string(sequence));
  return e;
}

int publish_faults(const Options& o) {
  install_signal_handlers();
  const auto deadline = deadline_after(o.timeout_s);
  DdsContext ctx(o.dds);
  fdds::DataWriter& writer = ctx.create_writer<fdi::FaultEvent>(profiles::kFaultEventWriter);
  unsigned writes = 0;
  unsigned instances = 0;
  for (unsigned v = 0; v < o.vessels; ++v) {
    for (unsigned s = 0; s < o.sensors; ++s) {
      if (o.sensor && s != *o.sensor) continue;
      fdi::FaultEvent e = make_event(o.mmsi_base + v, s, o.state, o.sequence);
      if (o.message) e.message(*o.message);
      usvfdi::dds::write(writer, e);
      ++writes;
      ++instances;
    }
  }
  if (o.rewrite_state) {
    usvfdi::dds::write(writer, make_event(o.mmsi_base, 0, *o.rewrite_state, o.sequence + 1));
    ++writes;
  }
  std::printf("published instances=%u writes=%u\n", instances, writes);
  std::fflush(stdout);
  while (!g_stop.load() && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const bool by_signal = g_stop.load();
  std::printf("stopping reason=%s\n", by_signal ? "signal" : "timeout");
  std::fflush(stdout);
  return by_signal ? 0 : 2;
}

struct Seen {
  fdi::FaultEvent latest;
  std::size_t samples = 0;
};

int read_faults(const Options& o) {
  const auto deadline = deadline_after(o.timeout_s);
  DdsContext ctx(o.dds);
  fdds::DataReader& reader = ctx.create_reader<fdi::FaultEvent>(profiles::kFaultEventReader);

  fdds::StatusCondition& condition = reader.get_statuscondition();
  condition.set_enabled_statuses(fdds::StatusMask::data_available());
  fdds::WaitSet waitset;
  waitset.attach_condition(condition);

  std::map<std::pair<std::uint32_t, unsigned>, Seen> seen;
  std::optional<Clock::time_point> settle_until;
  std::vector<fdi::FaultEvent> batch;
  for (;;) {
    const auto now = Clock::now();
    if (settle_until ? now >= *settle_until : now >= deadline) break;
    // Bounded wait; the take below also runs on timeout (polling fallback).
    fdds::ConditionSeq active;
    (void)waitset.wait(active, eprosima::fastrtps::Duration_t(0, 100000000));
    batch.clear();
    usvfdi::dds::take_all(reader, batch);
    for (const auto& e : batch) {
      Seen& s = seen[{e.mmsi(), static_cast<unsigned>(e.sensor())}];
      if (s.samples == 0 || e.sequence() >= s.latest.sequence()) s.latest = e;
      ++s.samples;
    }
    if (!settle_until && seen.size() >= o.expect) {
      settle_until = Clock::now() + std::chrono::milliseconds(o.settle_ms);
    }
  }
  (void)waitset.detach_condition(condition);

  for (const auto& [key, s] : seen) {
    std::printf(
        "instance mmsi=%u sensor=%u state=%u kind=%u sequence=%llu samples=%zu message=%s\n",
        key.first, key.second, static_cast<unsigned>(s.latest.state()),
        static_cast<unsigned>(s.latest.kind()),
        static_cast<unsigned long long>(s.latest.sequence()), s.samples,
        s.latest.message().c_str());
  }
  std::fflush(stdout);
  if (seen.size() < o.expect) {
    std::fprintf(stderr, "read-faults: timeout, saw %zu of %u instances\n", seen.size(), o.expect);
    return 1;
  }
  return 0;
}

double number(const std::string& text, const std::string& where) {
  char* end = nullptr;
  const double x = std::strtod(text.c_str(), &end);  // accepts nan, inf
  if (end == text.c_str() || *end != '\0') throw UsageError(where + ": not a number: " + text);
  return x;
}

int publish_inputs(const Options& o) {
  if (o.mmsi == 0 || o.script.empty()) throw UsageError("--mmsi and --script are required");
  std::ifstream in(o.script);
  if (!in) throw UsageError("cannot read --script " + o.script);
  std::vector<std::vector<std::string>> lines;
  for (std::string line; std::getline(in, line);) {
    std::istringstream ls(line);
    std::vector<std::string> words;
    for (std::string w; ls >> w;) words.push_back(w);
    if (!words.empty() && words[0][0] != '#') lines.push_back(words);
  }
  install_signal_handlers();
  const auto deadline = deadline_after(o.timeout_s);
  DdsContext ctx(o.dds);
  fdds::DataWriter& ins = ctx.create_writer<fdi::InsSample>(profiles::kInsWriterReliable);
  fdds::DataWriter& rudder = ctx.create_writer<fdi::RudderSample>(profiles::kRudderWriterReliable);
  for (;;) {
    fdds::PublicationMatchedStatus a, b;
    ins.get_publication_matched_status(a);
    rudder.get_publication_matched_status(b);
    if (a.current_count > 0 && b.current_count > 0) break;
    if (Clock::now() >= deadline || g_stop.load()) {
      std::fprintf(stderr, "publish-inputs: no reader matched\n");
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the reader's side of the match
  std::uint64_t n_ins = 0, n_rudder = 0;
  const auto write_ins = [&](double t, double v, double r, bool vv, bool rv) {
    fdi::InsSample s;
    s.mmsi(o.mmsi);
    s.seq(++n_ins);
    s.stamp(t);
    s.v(v);
    s.r(r);
    s.v_valid(vv);
    s.r_valid(rv);
    usvfdi::dds::write(ins, s);
  };
  const auto write_rudder = [&](double t, double d, bool valid) {
    fdi::RudderSample s;
    s.mmsi(o.mmsi);
    s.seq(++n_rudder);
    s.stamp(t);
    s.delta(d);
    s.valid(valid);
    usvfdi::dds::write(rudder, s);
  };
  for (std::size_t i = 0; i < lines.size() && !g_stop.load(); ++i) {
    const auto& w = lines[i];
    const std::string where = o.script + ":" + std::to_string(i + 1);
    const auto arg = [&](std::size_t k) {
      if (k >= w.size()) throw UsageError(where + ": missing argument " + std::to_string(k));
      return number(w[k], where);
    };
    if (w[0] == "ins") {
      write_ins(arg(1), arg(2), arg(3), w.size() > 4 ? arg(4) != 0 : true,
                w.size() > 5 ? arg(5) != 0 : true);
    } else if (w[0] == "rudder") {
      write_rudder(arg(1), arg(2), w.size() > 3 ? arg(3) != 0 : true);
    } else if (w[0] == "both" || w[0] == "insonly") {
      const double t0 = arg(1), t1 = arg(2), dt = arg(3), pace = arg(4);
      for (int k = 0; !g_stop.load(); ++k) {
        const double t = t0 + dt * k;
        if (t >= t1 - 1e-9) break;
        if (w[0] == "both") write_rudder(t, 0.1 * std::sin(0.5 * t), true);
        write_ins(t, 0.01 * std::sin(0.7 * t) + 0.001 * std::sin(13 * t),
                  0.002 * std::cos(0.3 * t) + 0.0002 * std::cos(11 * t), true, true);
        if (pace > 0) std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(pace));
      }
    } else if (w[0] == "skip") {
      n_ins += static_cast<std::uint64_t>(arg(1));
      n_rudder += static_cast<std::uint64_t>(arg(1));
    } else if (w[0] == "sleep") {
      std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(arg(1)));
    } else {
      throw UsageError(where + ": unknown command '" + w[0] + "'");
    }
  }
  // Every sample acknowledged by the readers before the writers go away.
  ins.wait_for_acknowledgments(eprosima::fastrtps::Duration_t(5, 0));
  rudder.wait_for_acknowledgments(eprosima::fastrtps::Duration_t(5, 0));
  std::printf("published ins=%llu rudder=%llu\n", static_cast<unsigned long long>(n_ins),
              static_cast<unsigned long long>(n_rudder));
  std::fflush(stdout);
  return 0;
}

/// Takes every available sample, sleeping after each one in Fast DDS's receive thread.
class SlowListener : public fdds::DataReaderListener {
 public:
  explicit SlowListener(unsigned delay_ms) : delay_ms_(delay_ms) {}
  void on_data_available(fdds::DataReader* reader) override {
    using eprosima::fastrtps::types::ReturnCode_t;
    const bool events =
        reader->get_topicdescription()->get_type_name() == fdi::FaultEventPubSubType().getName();
    fdds::SampleInfo info;
    for (;;) {
      if (g_stop.load()) return;
      if (events) {
        fdi::FaultEvent e;
        if (reader->take_next_sample(&e, &info) != ReturnCode_t::RETCODE_OK) return;
        if (info.valid_data) {
          std::printf("event mmsi=%u sensor=%u sequence=%llu state=%u\n", e.mmsi(),
                      static_cast<unsigned>(e.sensor()),
                      static_cast<unsigned long long>(e.sequence()),
                      static_cast<unsigned>(e.state()));
          std::fflush(stdout);
        }
      } else {
        fdi::FdiStatus st;
        if (reader->take_next_sample(&st, &info) != ReturnCode_t::RETCODE_OK) return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms_));
    }
  }

 private:
  unsigned delay_ms_;
};

int slow_reader(const Options& o) {
  install_signal_handlers();
  DdsContext ctx(o.dds);
  SlowListener listener(o.delay_ms);
  fdds::DataReaderQos q = ctx.subscriber().get_default_datareader_qos();
  q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
  q.durability().kind = fdds::TRANSIENT_LOCAL_DURABILITY_QOS;
  q.history().kind = fdds::KEEP_ALL_HISTORY_QOS;
  // Room for 2 samples per instance (Fast DDS needs max_samples >= instances x per instance).
  q.resource_limits().max_samples = 8;
  q.resource_limits().max_instances = 4;
  q.resource_limits().max_samples_per_instance = 2;
  q.resource_limits().allocated_samples = 8;
  fdds::DataReader* events = ctx.subscriber().create_datareader(
      &ctx.topic(usvfdi::dds::TopicId::kFaultEvent), q, &listener);
  fdds::DataReader* status =
      ctx.subscriber().create_datareader(&ctx.topic(usvfdi::dds::TopicId::kStatus), q, &listener);
  if (events == nullptr || status == nullptr) {
    std::fprintf(stderr, "slow-reader: cannot create the readers\n");
    return 4;
  }
  std::printf("slow reader ready\n");
  std::fflush(stdout);
  while (!g_stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  (void)ctx.subscriber().delete_datareader(events);
  (void)ctx.subscriber().delete_datareader(status);
  return 0;
}

int flood_acks(const Options& o) {
  if (o.mmsi == 0) throw UsageError("--mmsi is required");
  install_signal_handlers();
  const auto deadline = deadline_after(o.timeout_s);
  DdsContext ctx(o.dds);
  fdds::DataWriter& w = ctx.create_writer<fdi::FaultAck>(profiles::kFaultAckWriter);
  for (;;) {
    fdds::PublicationMatchedStatus m;
    w.get_publication_matched_status(m);
    if (m.current_count > 0) break;
    if (Clock::now() >= deadline || g_stop.load()) {
      std::fprintf(stderr, "flood-acks: no ack reader matched\n");
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::printf("flooding\n");
  std::fflush(stdout);
  std::uint64_t n = 0;
  fdi::FaultAck a;
  a.mmsi(o.mmsi);
  a.operator_id("flood");
  while (!g_stop.load() && Clock::now() < deadline) {
    const std::uint64_t k = n++;
    a.sensor(static_cast<std::uint8_t>(k % 5 == 4 ? 7 : k % 2));  // 7: no such sensor
    a.sequence(k % 7 == 6 ? 0 : 1000000 + k);                     // never a current one
    a.stamp(static_cast<double>(k));
    (void)w.write(&a);  // RELIABLE: blocks (at most max_blocking_time) when the reader lags
  }
  std::printf("flooded acks=%llu\n", static_cast<unsigned long long>(n));
  std::fflush(stdout);
  return 0;
}

int read_inputs(const Options& o) {
  if (o.mmsi == 0) throw UsageError("--mmsi is required");
  install_signal_handlers();
  const auto deadline = deadline_after(o.timeout_s);
  DdsContext ctx(o.dds);
  fdds::DataReader& reader = ctx.create_reader<fdi::RudderSample>(profiles::kRudderReaderReliable);
  fdds::StatusCondition& condition = reader.get_statuscondition();
  condition.set_enabled_statuses(fdds::StatusMask::data_available());
  fdds::WaitSet waitset;
  waitset.attach_condition(condition);
  std::printf("reading\n");
  std::fflush(stdout);
  std::vector<fdi::RudderSample> batch;
  while (!g_stop.load() && Clock::now() < deadline) {
    fdds::ConditionSeq active;
    (void)waitset.wait(active, eprosima::fastrtps::Duration_t(0, 100000000));
    batch.clear();
    usvfdi::dds::take_all(reader, batch);
    for (const auto& r : batch) {
      if (r.mmsi() != o.mmsi) continue;
      std::printf("rudder stamp=%.9f delta=%.17g valid=%d\n", r.stamp(), r.delta(),
                  r.valid() ? 1 : 0);
    }
    std::fflush(stdout);
  }
  (void)waitset.detach_condition(condition);
  return 0;
}

int writer_qos(const Options& o) {
  if (o.writer_profile.empty()) throw UsageError("--writer-profile is required");
  DdsContext ctx(o.dds);  // loads the profiles exactly as the service does
  fdds::DataWriterQos q;
  if (ctx.publisher().get_datawriter_qos_from_profile(o.writer_profile, q) !=
      eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
    std::fprintf(stderr, "writer-qos: no data writer profile '%s'\n", o.writer_profile.c_str());
    return 4;
  }
  std::printf("reliability=%d durability=%d depth=%d max_instances=%d\n",
              static_cast<int>(q.reliability().kind), static_cast<int>(q.durability().kind),
              q.history().depth, q.resource_limits().max_instances);
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
    if (o.mode == "writer-qos") return writer_qos(o);
    if (o.mode == "publish-inputs") return publish_inputs(o);
    if (o.mode == "slow-reader") return slow_reader(o);
    if (o.mode == "flood-acks") return flood_acks(o);
    if (o.mode == "read-inputs") return read_inputs(o);
    return o.mode == "publish-faults" ? publish_faults(o) : read_faults(o);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "usv_fdi_dds_probe: %s\n", e.what());
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "usv_fdi_dds_probe: %s\n", e.what());
    return 4;
  }
}
