// The sidecar's live NMEA input (include/usv_fdi/dds_service/nmea_input.hpp).
#include "usv_fdi/dds_service/nmea_input.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "usv_fdi/core/text.hpp"

namespace usvfdi::dds_service {

namespace {

constexpr int kPollMs = 100;

std::string seconds_text(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f s", s);
  return buf;
}

}  // namespace

NmeaInput::NmeaInput(const nmea_udp::ReceiverConfig& config, pipeline::FdiPipeline* pipeline,
                     LogSink log, double log_period)
    : config_(config),
      rx_(std::make_unique<nmea_udp::NmeaUdpReceiver>(config)),
      pipeline_(pipeline),
      log_(std::move(log)),
      log_period_(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
          std::chrono::duration<double>(log_period))) {}

NmeaInput::~NmeaInput() { stop(); }

void NmeaInput::start() {
  if (started_) return;
  started_ = true;
  last_log_ = std::chrono::steady_clock::now() - log_period_;  // the first refusal at once
  thread_ = std::thread([this] { loop(); });
}

void NmeaInput::stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

std::string NmeaInput::status_note() const {
  std::lock_guard<std::mutex> lock(m_);
  return note_;
}

nmea_udp::DecoderStats NmeaInput::stats() const {
  std::lock_guard<std::mutex> lock(m_);
  return stats_;
}

void NmeaInput::loop() {
  while (!stop_.load()) {
    const int n = rx_->poll(kPollMs);
    const auto now = std::chrono::steady_clock::now();
    if (n < 0) {
      // Not expected on a bound UDP socket; said (a few times), then retried after a pause.
      if (socket_errors_++ < 5) log(3, std::string("NMEA input: receive: ") + std::strerror(errno));
      std::this_thread::sleep_for(std::chrono::milliseconds(kPollMs));
    } else if (n > 0) {
      last_datagram_ = now;
      any_datagram_ = true;
    }
    hand_over();
    review(now);
  }
}

void NmeaInput::hand_over() {
  for (const nmea::AssembledSample& a : rx_->decoder().take()) {
    // Rudder first: the pipeline pairs an INS sample with the rudder angle at its stamp.
    if (!std::isnan(a.delta)) pipeline_->push_rudder(pipeline::RudderInput{a.t, a.delta, true, 0});
    const bool v_ok = !std::isnan(a.v);
    const bool r_ok = !std::isnan(a.r);
    // The surge speed (VBW's water speed, else VTG's) rides with the INS sample.
    if (v_ok || r_ok) pipeline_->push_ins(pipeline::InsInput{a.t, a.v, a.r, v_ok, r_ok, 0, a.u});
  }
}

/// Brings the status note up to date and logs what changed (stopped sentences, silence, bad
/// lines at most once per log period).
void NmeaInput::review(std::chrono::steady_clock::time_point now) {
  const nmea_udp::DatagramDecoder& d = rx_->decoder();
  if (!origin_logged_ && d.first_tag_ms() >= 0) {
    origin_logged_ = true;
    log(1, "NMEA input: first datagram; time base t = 0 s at TAG time c: " +
               utc_text(static_cast<double>(d.first_tag_ms()) / 1000.0) +
               " (sample times are TAG times less this)");
  } else if (!origin_logged_ && any_datagram_ && !std::isnan(d.latest_time())) {
    origin_logged_ = true;
    log(1,
        "NMEA input: first datagram without a TAG time c:; time base t = 0 s at its arrival "
        "(monotonic receive clock)");
  }
  std::string note;
  std::set<std::string> stale_now;
  for (const nmea::StaleInput& s : d.stale()) {
    if (s.quantity == "u") continue;  // the surge speed is optional: the engine holds the last
    stale_now.insert(s.sentence);
    note += "NMEA " + s.sentence + " stale " + seconds_text(s.age_s) + " (" + s.quantity + "); ";
    if (!stale_logged_.count(s.sentence)) {
      log(2, "NMEA input: " + s.sentence + " (" + s.quantity + ") has stopped: " +
                 (s.never_received ? "never received, " : "no valid value for ") +
                 seconds_text(s.age_s) + " of source time");
    }
  }
  for (const std::string& s : stale_logged_) {
    if (!stale_now.count(s)) log(1, "NMEA input: " + s + " is back");
  }
  stale_logged_ = stale_now;

  const double silent_s =
      any_datagram_ ? std::chrono::duration<double>(now - last_datagram_).count() : 0.0;
  if (any_datagram_ && silent_s > config_.assembler.max_age_s) {
    note += "NMEA no datagram for " + seconds_text(silent_s) + "; ";
    if (!silent_logged_) {
      log(2, "NMEA input: no datagram on " + rx_->describe() + " for " + seconds_text(silent_s));
      silent_logged_ = true;
    }
  } else if (silent_logged_ && any_datagram_) {
    log(1, "NMEA input: datagrams arrive again on " + rx_->describe());
    silent_logged_ = false;
  }

  const nmea_udp::DecoderStats& st = d.stats();
  if (st.lost_lines > 0) note += "NMEA " + std::to_string(st.lost_lines) + " lines lost; ";
  if (st.bad > 0) note += "NMEA " + std::to_string(st.bad) + " bad lines; ";

  if (now - last_log_ >= log_period_ && (st.bad > bad_logged_ || st.lost_lines > lost_logged_)) {
    last_log_ = now;
    std::vector<std::string> examples = rx_->decoder().take_examples();
    std::string text;
    for (std::size_t i = 0; i < examples.size() && i < 3; ++i) {
      text += (text.empty() ? "" : "; ") + examples[i];
    }
    log(2, "NMEA input: " + std::to_string(st.bad - bad_logged_) + " line(s) refused and " +
               std::to_string(st.lost_lines - lost_logged_) + " lost since the last report (" +
               std::to_string(st.bad) + " refused since start: " + st.describe() + ")" +
               (text.empty() ? std::string() : "; e.g. " + text));
    bad_logged_ = st.bad;
    lost_logged_ = st.lost_lines;
  }

  std::lock_guard<std::mutex> lock(m_);
  note_ = note;
  stats_ = st;
}

}  // namespace usvfdi::dds_service
