// usv-fdi monitor: the shore-side subscriber. Late-join aware (RELIABLE + TRANSIENT_LOCAL
// reader sized for a fleet): on start it receives the latched state of every fault instance.
#include <spdlog/spdlog.h>

#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>

#include <chrono>
#include <cstdio>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "commands.hpp"
#include "dds_options.hpp"
#include "usv_fdi/dds_service/convert.hpp"
#include "usv_fdi/io/config.hpp"
#include "usv_fdi/io/jsonl.hpp"

namespace usvfdi::app {
namespace {

namespace dds = usv_fdi::dds;
using eprosima::fastdds::dds::ConditionSeq;
using eprosima::fastdds::dds::DataReader;
using eprosima::fastdds::dds::DataWriter;
using eprosima::fastdds::dds::StatusMask;
using eprosima::fastdds::dds::WaitSet;
using Clock = std::chrono::steady_clock;

struct MonitorArgs {
  DdsCli dds;
  std::vector<std::uint32_t> mmsi;  ///< filter (empty: every vessel)
  bool json = false;
  std::vector<std::string> acks;  ///< MMSI:SENSOR:SEQUENCE
  std::string operator_id = "operator";
  double duration = 0.0;  ///< stop after this long (0: until a signal)
  bool once = false;      ///< print the latched state after --duration (default 3 s) and exit
  int expect = 0;         ///< stop once this many instances are known
};

struct Row {
  std::uint32_t mmsi = 0;
  FaultEvent ev;
  Clock::time_point received;
};

std::string json_row(const Row& r) {
  std::ostringstream os;
  const FaultEvent& e = r.ev;
  os << "{\"type\":\"fault\",\"mmsi\":" << r.mmsi << ",\"sensor\":\"" << to_string(e.sensor)
     << "\",\"state\":\"" << to_string(e.state) << "\",\"kind\":\"" << to_string(e.kind)
     << "\",\"c_a\":" << io::json_number(e.c_a) << ",\"c_g\":" << io::json_number(e.c_g)
     << ",\"statistic\":" << io::json_number(e.statistic)
     << ",\"threshold\":" << io::json_number(e.threshold)
     << ",\"onset_time\":" << io::json_number(e.onset_time)
     << ",\"detection_time\":" << io::json_number(e.detection_time)
     << ",\"sequence\":" << e.sequence << ",\"a\":[" << io::json_number(e.A(0, 0)) << ","
     << io::json_number(e.A(0, 1)) << "," << io::json_number(e.A(1, 0)) << ","
     << io::json_number(e.A(1, 1)) << "],\"message\":" << io::json_string(e.message) << "}";
  return os.str();
}

void print_table(const std::map<std::pair<std::uint32_t, int>, Row>& rows) {
  const auto now = Clock::now();
  std::printf("%-10s %-13s %-20s %-8s %5s %5s %5s %7s  %s\n", "MMSI", "SENSOR", "STATE", "KIND",
              "C_A", "C_G", "SEQ", "AGE[s]", "MESSAGE");
  for (const auto& [key, r] : rows) {
    const double age = std::chrono::duration<double>(now - r.received).count();
    std::printf("%-10u %-13s %-20s %-8s %5.2f %5.2f %5llu %7.1f  %s\n", r.mmsi,
                to_string(r.ev.sensor), to_string(r.ev.state), to_string(r.ev.kind), r.ev.c_a,
                r.ev.c_g, static_cast<unsigned long long>(r.ev.sequence), age,
                r.ev.message.c_str());
  }
  std::printf("(%zu fault instances)\n", rows.size());
  std::fflush(stdout);
}

bool parse_ack(const std::string& spec, fdi::FaultAck* out, std::string* why) {
  std::stringstream ss(spec);
  std::string m, s, q;
  if (!std::getline(ss, m, ':') || !std::getline(ss, s, ':') || !std::getline(ss, q) || m.empty() ||
      q.empty()) {
    *why = "--ack " + spec + ": expected MMSI:SENSOR:SEQUENCE";
    return false;
  }
  Sensor sensor;
  if (!parse_sensor(s, &sensor)) {
    *why = "--ack " + spec + ": sensor must be accelerometer, gyro or unknown";
    return false;
  }
  try {
    std::size_t pm = 0, pq = 0;
    const unsigned long mmsi = std::stoul(m, &pm);
    const unsigned long long seq = std::stoull(q, &pq);
    if (pm != m.size() || pq != q.size() || mmsi == 0 || mmsi > 999999999ul) throw 1;
    out->mmsi(static_cast<std::uint32_t>(mmsi));
    out->sensor(static_cast<std::uint8_t>(sensor));
    out->sequence(seq);
  } catch (...) {
    *why = "--ack " + spec + ": MMSI and SEQUENCE must be positive integers";
    return false;
  }
  return true;
}

int send_acks(dds::DdsContext& ctx, const MonitorArgs& a) {
  std::vector<fdi::FaultAck> acks;
  for (const std::string& spec : a.acks) {
    fdi::FaultAck ack;
    std::string why;
    if (!parse_ack(spec, &ack, &why)) {
      spdlog::error("{}", why);
      return kExitUsage;
    }
    ack.operator_id(a.operator_id.substr(0, 63).c_str());
    ack.stamp(
        std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count());
    acks.push_back(ack);
  }
  DataWriter& w = ctx.create_writer(dds::TopicId::kFaultAck, dds::profiles::kFaultAckWriter);
  // Wait (bounded) until a sidecar's ack reader is matched, so the ack is not lost.
  eprosima::fastdds::dds::PublicationMatchedStatus st;
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  while (Clock::now() < deadline) {
    w.get_publication_matched_status(st);
    if (st.current_count > 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (st.current_count == 0) {
    spdlog::error("no sidecar subscribes to acknowledgements on this domain/partition (5 s)");
    return kExitFailure;
  }
  for (const fdi::FaultAck& ack : acks) {
    dds::write(w, ack);
    spdlog::info("ack sent: MMSI {} {} #{} by {}", ack.mmsi(),
                 to_string(static_cast<Sensor>(ack.sensor())), ack.sequence(), a.operator_id);
  }
  w.wait_for_acknowledgments(eprosima::fastrtps::Duration_t(3, 0));
  return kExitOk;
}

int run_monitor(const MonitorArgs& a) {
  block_stop_signals();
  dds::DdsConfig cfg;
  try {
    cfg = make_dds_config(a.dds);
  } catch (const io::ConfigError& e) {
    spdlog::error("{}", e.what());
    return kExitConfig;
  }
  std::unique_ptr<dds::DdsContext> ctx;
  try {
    ctx = std::make_unique<dds::DdsContext>(cfg);
  } catch (const std::exception& e) {
    spdlog::error("cannot join DDS domain {}: {}", cfg.domain_id, e.what());
    return kExitFailure;
  }
  if (!a.acks.empty()) {
    const int rc = send_acks(*ctx, a);
    if (rc != kExitOk || (!a.once && a.duration == 0.0 && a.expect == 0)) return rc;
  }
  DataReader& reader =
      ctx->create_reader(dds::TopicId::kFaultEvent, dds::profiles::kFaultEventReader);
  reader.get_statuscondition().set_enabled_statuses(StatusMask::data_available());
  WaitSet ws;
  ws.attach_condition(reader.get_statuscondition());

  const std::set<std::uint32_t> filter(a.mmsi.begin(), a.mmsi.end());
  std::map<std::pair<std::uint32_t, int>, Row> rows;
  const double duration = a.once && a.duration == 0.0 ? 3.0 : a.duration;
  const auto start = Clock::now();
  std::vector<fdi::FaultEvent> buf;
  for (;;) {
    ConditionSeq active;
    ws.wait(active, eprosima::fastrtps::Duration_t(0, 200000000));
    buf.clear();
    dds::take_all(reader, buf);
    bool changed = false;
    for (const fdi::FaultEvent& d : buf) {
      if (!filter.empty() && !filter.count(d.mmsi())) continue;
      Row r;
      r.mmsi = d.mmsi();
      if (!service::from_dds(d, &r.ev)) {
        spdlog::warn("ignored a FaultEvent from MMSI {} with unknown sensor/state/kind", d.mmsi());
        continue;
      }
      r.received = Clock::now();
      rows[{r.mmsi, static_cast<int>(r.ev.sensor)}] = r;
      changed = true;
      if (a.json && !a.once) {
        std::printf("%s\n", json_row(r).c_str());
        std::fflush(stdout);
      }
    }
    if (changed && !a.json && !a.once) print_table(rows);
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    const bool enough = a.expect > 0 && static_cast<int>(rows.size()) >= a.expect;
    if (enough || (duration > 0 && elapsed >= duration) || wait_for_stop_signal(0.0) != 0) break;
  }
  if (a.once) {
    if (a.json) {
      for (const auto& [key, r] : rows) std::printf("%s\n", json_row(r).c_str());
    } else {
      print_table(rows);
    }
  }
  if (a.expect > 0 && static_cast<int>(rows.size()) < a.expect) {
    spdlog::error("saw {} fault instances, expected {}", rows.size(), a.expect);
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace

void register_monitor_command(CommandRegistry& registry) {
  static MonitorArgs args;
  CLI::App* sub =
      registry.add("monitor",
                   "shore-side view of every vessel's latched faults (late-join aware); --ack to "
                   "acknowledge",
                   [] { return run_monitor(args); });
  add_dds_options(sub, &args.dds);
  sub->add_option("--mmsi", args.mmsi, "only these vessels (repeatable)");
  sub->add_flag("--json", args.json, "JSON Lines instead of a table");
  sub->add_option("--ack", args.acks, "acknowledge MMSI:SENSOR:SEQUENCE (repeatable)");
  sub->add_option("--operator", args.operator_id, "operator id sent with --ack")
      ->capture_default_str();
  sub->add_option("--duration", args.duration, "stop after this many seconds (0: on a signal)")
      ->check(CLI::NonNegativeNumber);
  sub->add_flag("--once", args.once,
                "wait --duration (default 3 s) for the latched state, print it once, exit");
  sub->add_option("--expect", args.expect, "exit 0 once this many fault instances are known")
      ->check(CLI::NonNegativeNumber);
}

}  // namespace usvfdi::app
