// usv-fdi bridge: the vessel's alerts on the bridge alert management system (IEC 62923 BAM)
// over an IEC 61162-450 network, and the bridge's acknowledgements back to the sidecar.
//
// A DDS participant next to the sidecar: it reads the vessel's latched FaultEvents (as the
// monitor does, ownership checked) and writes, as UDP datagrams ("UdPbC\0", a TAG block with
// the source identification and line count, then the sentences):
//   * ALF for every change of an instance (and for every instance when it starts);
//   * ALC, the list of the alerts that are not normal, every --alc-period s;
//   * HBT every --hbt-period s: status A while the sidecar is heard, V (system fail) before
//     it is first heard and when it falls silent.
// It reads ACN datagrams (IEC 61162-450 or plain NMEA 0183 lines) and, for one of its alerts:
// acknowledge -> a FaultAck of the revision in force to the sidecar (an ALF with the next
// revision follows the sidecar's confirmation); request/repeat -> the alert's ALF again;
// silence, responsibility transfer, nothing to acknowledge, or no confirmation within
// --ack-timeout -> ARC. ACNs for other equipment's alerts are ignored; bad datagrams and
// sentences are counted by reason and logged (rate-limited), and never act.

#include <spdlog/spdlog.h>

#include <fastdds/dds/publisher/DataWriter.hpp>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "ack_protocol.hpp"
#include "bridge_alerts.hpp"
#include "commands.hpp"
#include "dds_options.hpp"
#include "fleet_view.hpp"
#include "usv_fdi/core/text.hpp"
#include "usv_fdi/io/config.hpp"
#include "usv_fdi/nmea/datagram.hpp"
#include "usv_fdi/nmea_udp/udp.hpp"

namespace usvfdi::app {
namespace {

using Clock = std::chrono::steady_clock;

struct BridgeArgs {
  DdsCli dds;
  std::uint32_t mmsi = 0;
  std::string out = "239.192.0.17:60017";  ///< IEC 61162-450 transmission group BAM1
  std::string in = "239.192.0.17:60017";
  std::string interface_address = "0.0.0.0";
  std::string source = "UF0001";  ///< SFI in the TAG block (s:)
  BridgeAlertConfig alerts;
  std::string category = "B";
  std::string priority = "warning";
  double alc_period = 30.0;
  double hbt_period = 5.0;
  double ack_timeout = 5.0;
  double silent_after = 5.0;
  std::string operator_prefix = "bridge";
};

/// Counts of what was received and did not act, logged with a rate limit: the first 5 of each
/// reason, then every 100th.
class Rejections {
 public:
  void count(const std::string& reason, const std::string& detail) {
    const std::uint64_t n = ++counts_[reason];
    if (n <= 5 || n % 100 == 0) {
      spdlog::warn("bridge input: {} ({} so far): {}", reason, n, escape_text(detail));
    }
  }
  std::string summary() const {
    std::string s;
    for (const auto& [reason, n] : counts_) {
      s += (s.empty() ? "" : ", ") + std::to_string(n) + " " + reason;
    }
    return s.empty() ? "none" : s;
  }

 private:
  std::map<std::string, std::uint64_t> counts_;
};

/// One ACN acknowledge waiting for the sidecar's confirmation.
struct PendingAck {
  AckRequest req;
  nmea::Acn acn;
  Clock::time_point deadline;
};

class Bridge {
 public:
  Bridge(const BridgeArgs& a, dds::DdsContext& ctx, FleetView& view,
         std::unique_ptr<nmea_udp::NmeaUdpSender> tx, std::unique_ptr<nmea_udp::UdpListener> rx)
      : a_(a), ctx_(ctx), view_(view), tx_(std::move(tx)), rx_(std::move(rx)) {
    ack_writer_ =
        &ctx.create_writer_in_partitions(dds::TopicId::kFaultAck, dds::profiles::kFaultAckWriter,
                                         ack_partitions(ctx.config().publisher_partitions, a.mmsi));
  }

  /// One turn: DDS, then ACNs, confirmations and the periodic sentences.
  void turn() {
    view_.poll(0.05);
    send_changes();
    read_acns();
    check_pending();
    const auto now = Clock::now();
    if (now >= next_alc_) {
      send_alc();
      next_alc_ = now + seconds(a_.alc_period);
    }
    if (now >= next_hbt_) {
      send_hbt();
      next_hbt_ = now + seconds(a_.hbt_period);
    }
  }

  std::string summary() const {
    return std::to_string(sent_) + " datagrams sent (" + std::to_string(alf_messages_) +
           " ALF messages), " + std::to_string(acks_sent_) + " acks sent, " +
           std::to_string(arcs_) + " ARC; not acted on: " + rejections_.summary();
  }

 private:
  static Clock::duration seconds(double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  }

  std::vector<Row> rows() const {
    std::vector<Row> out;
    view_.rows().for_each([&](const RowKey& key, const Row& r) {
      if (key.first == a_.mmsi) out.push_back(r);
    });
    return out;
  }

  const Row* row_of(Sensor s) const { return view_.row(RowKey{a_.mmsi, static_cast<int>(s)}); }

  void send(const std::vector<std::string>& sentences) {
    if (sentences.empty()) return;
    nmea::TagBlock tag;
    tag.source = a_.source;
    line_count_ = line_count_ >= 999 ? 1 : line_count_ + 1;
    tag.line_count = line_count_;
    const auto d = nmea::format_iec450_datagram(tag, sentences);
    if (!d.ok()) {
      spdlog::error("bridge: cannot format a datagram: {}", d.rejection().text);
      return;
    }
    if (!tx_->send(d.value())) {
      spdlog::warn("bridge: sending to {} failed: {}", a_.out, std::strerror(errno));
      return;
    }
    ++sent_;
  }

  void send_alf(const Row& r) {
    send(alf_sentences(a_.alerts, r, alf_messages_ % 10, utc_time_of(wall_now())));
    ++alf_messages_;
  }

  /// An ALF for every instance whose sequence or state changed since the last one sent.
  void send_changes() {
    for (const Row& r : rows()) {
      // The incarnation too: a sidecar restarted without its state raises #1 again.
      auto& last = shown_[static_cast<int>(r.ev.sensor)];
      const auto now = std::make_tuple(r.ev.incarnation, r.ev.sequence, r.ev.state);
      if (last == now) continue;
      last = now;
      spdlog::info("bridge: ALF {} {} revision {} ({} #{})", to_string(r.ev.sensor),
                   static_cast<char>(alert_state(r.ev.state)), alert_revision(r.ev.sequence),
                   to_string(r.ev.state), r.ev.sequence);
      send_alf(r);
    }
  }

  void send_alc() {
    const auto s =
        nmea::format_alc_list(a_.alerts.talker, alc_message_id_, alc_entries(a_.alerts, rows()));
    alc_message_id_ = (alc_message_id_ + 1) % 100;
    if (s.ok()) send(s.value());
  }

  void send_hbt() {
    nmea::Hbt h;
    h.talker = a_.alerts.talker;
    h.interval_s = a_.hbt_period;
    // Status A while the sidecar is heard (its periodic FdiStatus); V (system fail) before it
    // is first heard and once it has been silent for --silent-after s: the FDI is not working.
    const double age = view_.heard_age(a_.mmsi);
    h.normal = age <= a_.silent_after;  // false for NaN: never heard
    if (h.normal != equipment_normal_) {
      equipment_normal_ = h.normal;
      if (h.normal) {
        spdlog::info("bridge: the sidecar of MMSI {} is heard: HBT status A", a_.mmsi);
      } else {
        spdlog::warn("bridge: the sidecar of MMSI {} is {}: HBT status V", a_.mmsi,
                     std::isnan(age) ? "not heard yet" : "silent");
      }
    }
    h.sequence = hbt_sequence_;
    hbt_sequence_ = (hbt_sequence_ + 1) % 10;
    const auto s = nmea::format_hbt(h);
    if (s.ok()) send({s.value()});
  }

  void send_arc(const nmea::Acn& acn, const std::string& why) {
    nmea::Arc arc;
    arc.talker = a_.alerts.talker;
    arc.time = utc_time_of(wall_now());
    arc.alert = acn.alert;
    arc.refused = acn.command;
    const auto s = nmea::format_arc(arc);
    spdlog::warn("bridge: ACN {} of alert {} refused: {}", static_cast<char>(acn.command),
                 acn.alert.id, why);
    if (s.ok()) send({s.value()});
    ++arcs_;
  }

  void read_acns() {
    rx_->read(0, [this](std::string_view bytes, const std::string& who) {
      const auto d = nmea::parse_datagram(bytes);
      if (!d.ok()) {
        rejections_.count(nmea::to_string(d.rejection().reason),
                          "datagram from " + who + ": " + d.rejection().text);
        return;
      }
      for (const auto& line : d.value().lines) {
        if (!line.ok()) {
          rejections_.count(nmea::to_string(line.rejection().reason),
                            "from " + who + ": " + line.rejection().text);
          continue;
        }
        on_sentence(line.value(), who);
      }
    });
  }

  void on_sentence(const nmea::TaggedSentence& ts, const std::string& who) {
    const nmea::Sentence& s = ts.sentence;
    if (s.formatter != "ACN") return;  // the network carries everything; only ACN is ours
    const auto acn = nmea::parse_acn(s);
    if (!acn.ok()) {
      rejections_.count(std::string("ACN ") + nmea::to_string(acn.rejection().reason),
                        "from " + who + ": " + acn.rejection().text);
      return;
    }
    const Row* row = nullptr;
    if (const auto sensor = sensor_of(a_.alerts, acn.value().alert)) row = row_of(*sensor);
    const AcnAction act = judge_acn(a_.alerts, a_.mmsi, acn.value(), row);
    switch (act.what) {
      case AcnAction::kNotOurs:
        return;
      case AcnAction::kRepeat:
        if (row != nullptr) {
          send_alf(*row);
        } else {
          Row normal;
          normal.mmsi = a_.mmsi;
          normal.ev.sensor = act.sensor;
          send_alf(normal);
        }
        return;
      case AcnAction::kRefuse:
        send_arc(acn.value(), act.why);
        return;
      case AcnAction::kAcknowledge:
        break;
    }
    for (const PendingAck& p : pending_) {
      if (p.req.sensor == act.ack.sensor && p.req.sequence == act.ack.sequence) {
        spdlog::info("bridge: ACN for {} #{} repeated while its acknowledgement is pending",
                     to_string(act.ack.sensor), act.ack.sequence);
        return;  // one FaultAck, one answer
      }
    }
    fdds::PublicationMatchedStatus st;
    ack_writer_->get_publication_matched_status(st);
    if (st.current_count == 0) {
      send_arc(acn.value(), "no sidecar subscribes to acknowledgements of this vessel");
      return;
    }
    const std::string src = ts.tag && ts.tag->source ? *ts.tag->source : s.talker;
    fdi::FaultAck ack;
    ack.mmsi(a_.mmsi);
    ack.sensor(static_cast<std::uint8_t>(act.ack.sensor));
    ack.sequence(act.ack.sequence);
    ack.operator_id((a_.operator_prefix + ":" + src).substr(0, 63).c_str());
    ack.stamp(wall_now());
    ack.incarnation(row->ev.incarnation);
    dds::write(*ack_writer_, ack);
    ++acks_sent_;
    spdlog::info("bridge: ACN from {} ({}) acknowledges {} #{}: ack sent", escape_text(src), who,
                 to_string(act.ack.sensor), act.ack.sequence);
    pending_.push_back({act.ack, acn.value(), Clock::now() + seconds(a_.ack_timeout)});
  }

  void check_pending() {
    for (auto it = pending_.begin(); it != pending_.end();) {
      const Row* r = row_of(it->req.sensor);
      if (ack_confirmed(it->req, r)) {
        spdlog::info("bridge: acknowledgement of {} #{} confirmed by the sidecar",
                     to_string(it->req.sensor), it->req.sequence);
        it = pending_.erase(it);
      } else if (Clock::now() >= it->deadline) {
        send_arc(it->acn, "not confirmed by the sidecar within " + std::to_string(a_.ack_timeout) +
                              " s: " + refusal_reason(it->req, r));
        it = pending_.erase(it);
      } else {
        ++it;
      }
    }
  }

  const BridgeArgs& a_;
  dds::DdsContext& ctx_;
  FleetView& view_;
  std::unique_ptr<nmea_udp::NmeaUdpSender> tx_;
  std::unique_ptr<nmea_udp::UdpListener> rx_;
  fdds::DataWriter* ack_writer_ = nullptr;
  std::map<int, std::tuple<std::uint64_t, std::uint64_t, FaultState>> shown_;
  std::vector<PendingAck> pending_;
  Rejections rejections_;
  Clock::time_point next_alc_ = Clock::now(), next_hbt_ = Clock::now();
  int line_count_ = 0, alc_message_id_ = 0, hbt_sequence_ = 0;
  std::uint64_t sent_ = 0, alf_messages_ = 0, acks_sent_ = 0, arcs_ = 0;
  bool equipment_normal_ = true;  ///< what the last HBT said
};

/// The alert settings of the command line; false (logged) when one is wrong.
bool alert_settings(BridgeArgs* a) {
  if (a->category.size() != 1 || a->category.find_first_of("ABC") != 0) {
    spdlog::error("--category '{}' is not A, B or C", a->category);
    return false;
  }
  a->alerts.category = static_cast<nmea::AlertCategory>(a->category[0]);
  if (a->priority == "warning") {
    a->alerts.priority = nmea::AlertPriority::kWarning;
  } else if (a->priority == "caution") {
    a->alerts.priority = nmea::AlertPriority::kCaution;
  } else if (a->priority == "alarm") {
    a->alerts.priority = nmea::AlertPriority::kAlarm;
  } else {
    spdlog::error("--priority '{}' is not caution, warning or alarm", a->priority);
    return false;
  }
  const std::string why = check(a->alerts);
  if (!why.empty()) {
    spdlog::error("bridge alerts: {}", why);
    return false;
  }
  return true;
}

int run_bridge(BridgeArgs& a) {
  block_stop_signals();
  route_fastdds_log_to_spdlog();
  if (!alert_settings(&a)) return kExitUsage;
  std::unique_ptr<nmea_udp::NmeaUdpSender> tx;
  std::unique_ptr<nmea_udp::UdpListener> rx;
  try {
    const std::string iface = a.interface_address == "0.0.0.0" ? "" : a.interface_address;
    tx = std::make_unique<nmea_udp::NmeaUdpSender>(nmea_udp::parse_endpoint(a.out), iface, 1);
    rx = std::make_unique<nmea_udp::UdpListener>(nmea_udp::parse_endpoint(a.in), iface, 1 << 20,
                                                 "bridge ACN input");
  } catch (const std::invalid_argument& e) {
    spdlog::error("bridge: {}", e.what());
    return kExitUsage;
  } catch (const std::exception& e) {
    spdlog::error("bridge: cannot open the UDP sockets (out {}, in {}): {}", a.out, a.in, e.what());
    return kExitFailure;
  }
  dds::DdsConfig cfg;
  try {
    cfg = make_dds_config(a.dds);
  } catch (const io::ConfigError& e) {
    spdlog::error("{}", e.what());
    return kExitConfig;
  }
  MonitorArgs view_args;
  view_args.mmsi = {a.mmsi};
  view_args.silent_after = a.silent_after;
  std::unique_ptr<dds::DdsContext> ctx;
  std::unique_ptr<FleetView> view;
  std::unique_ptr<Bridge> bridge;
  try {
    ctx = std::make_unique<dds::DdsContext>(cfg);
    view = std::make_unique<FleetView>(*ctx, view_args);
    bridge = std::make_unique<Bridge>(a, *ctx, *view, std::move(tx), std::move(rx));
  } catch (const std::exception& e) {
    spdlog::error("cannot join DDS domain {}: {}", cfg.domain_id, e.what());
    return kExitFailure;
  }
  spdlog::info(
      "bridge for MMSI {}: alerts {} {}/{}/{} instance {} to {}, ACN from {} (domain {}): "
      "running",
      a.mmsi, a.alerts.manufacturer, a.alerts.alert_ids[0], a.alerts.alert_ids[1],
      a.alerts.alert_ids[2], a.alerts.instance, a.out, a.in, cfg.domain_id);
  while (wait_for_stop_signal(0.0) == 0) bridge->turn();
  spdlog::info("bridge stopped: {}", bridge->summary());
  return kExitOk;
}

}  // namespace

void register_bridge_command(CommandRegistry& registry) {
  static BridgeArgs args;
  CLI::App* sub = registry.add(
      "bridge",
      "the vessel's latched faults as IEC 62923 alerts (ALF, ALC, HBT) on an IEC 61162-450 "
      "network; ACN from the bridge acknowledges them",
      [] { return run_bridge(args); });
  add_dds_options(sub, &args.dds);
  sub->add_option("--mmsi", args.mmsi, "the vessel")->required()->check(CLI::Range(1u, 999999999u));
  sub->add_option("--out", args.out, "send the alert sentences to GROUP:PORT (or ADDRESS:PORT)")
      ->capture_default_str();
  sub->add_option("--in", args.in, "read ACN sentences at GROUP:PORT (or ADDRESS:PORT)")
      ->capture_default_str();
  sub->add_option("--interface", args.interface_address,
                  "IPv4 address of the interface for multicast (0.0.0.0: the system's choice)")
      ->capture_default_str();
  sub->add_option("--source", args.source, "source identification (TAG block s:)")
      ->capture_default_str();
  sub->add_option("--talker", args.alerts.talker, "talker of the sentences written")
      ->capture_default_str();
  sub->add_option("--manufacturer", args.alerts.manufacturer, "manufacturer mnemonic code")
      ->capture_default_str();
  sub->add_option("--alert-ids", args.alerts.alert_ids,
                  "alert identifiers of the accelerometer, gyro and unknown-sensor alerts")
      ->expected(3)
      ->delimiter(',')
      ->capture_default_str();
  sub->add_option("--instance", args.alerts.instance, "alert instance")->capture_default_str();
  sub->add_option("--category", args.category, "alert category A, B or C")->capture_default_str();
  sub->add_option("--priority", args.priority, "caution, warning or alarm")->capture_default_str();
  sub->add_option("--alc-period", args.alc_period, "cyclic alert list (ALC) period [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--hbt-period", args.hbt_period, "heartbeat (HBT) period [s]")
      ->check(CLI::Range(0.1, 999.0))
      ->capture_default_str();
  sub->add_option("--ack-timeout", args.ack_timeout,
                  "ARC when the sidecar has not confirmed an ACN's acknowledgement by then [s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--silent-after", args.silent_after,
                  "HBT status V (system fail) when the sidecar has not been heard for this long "
                  "[s]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--operator-prefix", args.operator_prefix,
                  "FaultAck operator id: PREFIX:SOURCE (the ACN's TAG source, else its talker)")
      ->capture_default_str();
}

}  // namespace usvfdi::app
