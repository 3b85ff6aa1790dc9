#include "usv_fdi/io/nmea_log.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <istream>
#include <ostream>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <utility>

#include "usv_fdi/io/csv.hpp"  // InputError
#include "usv_fdi/nmea/assembler.hpp"
#include "usv_fdi/nmea/datagram.hpp"
#include "usv_fdi/nmea/navigation.hpp"

namespace usvfdi::io {

namespace {

constexpr std::string_view kHeaderText{"UdPbC"};

/// The line without an IEC 61162-450 header ("UdPbC" and its NUL, which a text log may lack).
std::string_view strip_iec450_header(std::string_view line) {
  if (line.substr(0, kHeaderText.size()) != kHeaderText) return line;
  line.remove_prefix(kHeaderText.size());
  if (!line.empty() && line.front() == '\0') line.remove_prefix(1);
  return line;
}

double round_to(double x, int decimals) {
  const double scale = std::pow(10.0, decimals);
  const double y = std::round(x * scale) / scale;
  return y == 0.0 ? 0.0 : y;  // never "-0"
}

/// A finite value within +-limit, rounded to `decimals`; empty (a null field) otherwise.
std::optional<double> field_value(double x, double limit, int decimals) {
  if (!std::isfinite(x)) return std::nullopt;
  const double y = round_to(x, decimals);
  if (std::fabs(y) > limit) return std::nullopt;
  return y;
}

nmea::Status status_of(const std::optional<double>& x) {
  return x ? nmea::Status::kValid : nmea::Status::kInvalid;
}

constexpr double kRadToDeg = 180.0 / nmea::kPi;

}  // namespace

std::string NmeaLineStats::describe() const {
  std::string out;
  for (const auto& [reason, c] : reasons) {
    if (!out.empty()) out += ", ";
    out += std::to_string(c.count) + " " + reason + " (first: line " +
           std::to_string(c.first_line) + ")";
  }
  return out;
}

NmeaSampleReader::NmeaSampleReader(const std::string& path, const NmeaInputOptions& options)
    : NmeaSampleReader(nullptr, path, options) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw InputError(path, 0, "", "", std::string("cannot read: ") + std::strerror(EISDIR));
  }
  auto f = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!f->is_open()) {
    throw InputError(path, 0, "", "", std::string("cannot open: ") + std::strerror(errno));
  }
  in_ = std::move(f);
}

NmeaSampleReader::NmeaSampleReader(std::unique_ptr<std::istream> in, const std::string& name,
                                   const NmeaInputOptions& options)
    : in_(std::move(in)), name_(name), options_(options) {
  if (options.cycle_rate_hz &&
      !(std::isfinite(*options.cycle_rate_hz) && *options.cycle_rate_hz > 0.0)) {
    throw std::invalid_argument("NMEA sentence rate: must be finite and > 0");
  }
  nmea::AssemblerConfig ac;
  ac.rate_hz = options.grid_rate_hz;
  ac.max_age_s = options.max_age_s;
  ac.hold_until_due = options.hold_until_due;
  ac.rudder_sign = nmea::rudder_sign_from_b2(options.b2);
  assembler_ = std::make_unique<nmea::SampleAssembler>(ac);  // refuses a bad rate or age
}

NmeaSampleReader::~NmeaSampleReader() = default;

bool NmeaSampleReader::next(Sample* s) {
  while (next_pending_ == pending_.size()) {
    if (!refill()) return false;
  }
  *s = pending_[next_pending_++];
  ++rows_;
  return true;
}

/// Reads lines until the assembler emits samples (or the file ends: the last grid times).
bool NmeaSampleReader::refill() {
  pending_.clear();
  next_pending_ = 0;
  if (eof_) return false;
  std::string text;
  while (pending_.empty()) {
    if (!std::getline(*in_, text)) {
      eof_ = true;
      if (std::isfinite(latest_t_)) assembler_->advance(latest_t_);
    } else {
      ++line_;
      read_line(text);
    }
    for (const nmea::AssembledSample& a : assembler_->take()) {
      pending_.push_back(Sample{a.t, a.v, a.r, a.delta, a.u});
    }
    if (eof_) break;
  }
  return !pending_.empty();
}

void NmeaSampleReader::count(const std::string& reason, const std::string& text) {
  NmeaLineCount& c = stats_.reasons[reason];
  if (c.count == 0) {
    c.first_line = line_;
    c.first_text = text;
  }
  ++c.count;
  ++stats_.unusable;
}

std::optional<double> NmeaSampleReader::line_time(const std::string& address,
                                                  const std::optional<double>& tag_t) {
  if (tag_t) {
    last_tag_t_ = tag_t;
    return tag_t;
  }
  if (last_tag_t_) return last_tag_t_;
  if (!options_.cycle_rate_hz) return std::nullopt;
  // A cycle of sentences at the given rate ends when an address repeats.
  if (std::find(cycle_addresses_.begin(), cycle_addresses_.end(), address) !=
      cycle_addresses_.end()) {
    ++cycle_;
    cycle_addresses_.clear();
  }
  cycle_addresses_.push_back(address);
  return static_cast<double>(cycle_) / *options_.cycle_rate_hz;
}

void NmeaSampleReader::read_line(const std::string& raw) {
  std::string_view line(raw);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  if (line.find_first_not_of(" \t") == std::string_view::npos || line.front() == '#') return;
  ++stats_.lines;
  if (line.size() > kNmeaMaxLine) {
    count("too long", "longer than " + std::to_string(kNmeaMaxLine) + " bytes");
    return;
  }
  const nmea::Result<nmea::TaggedSentence> parsed =
      nmea::parse_tagged_sentence(strip_iec450_header(line));
  if (!parsed) {
    count(nmea::to_string(parsed.rejection().reason), parsed.rejection().text);
    return;
  }
  const nmea::TaggedSentence& ts = parsed.value();
  const nmea::Sentence& s = ts.sentence;
  std::optional<double> tag_t;
  if (ts.tag && ts.tag->unix_time_ms) {
    // Seconds since the log's first c: (exact in a double; UNIX seconds would lose the
    // fraction in the output's 9 significant digits).
    if (!first_tag_ms_) first_tag_ms_ = ts.tag->unix_time_ms;
    tag_t = static_cast<double>(*ts.tag->unix_time_ms - *first_tag_ms_) / 1000.0;
  }

  const std::string& f = s.formatter;
  if (!nmea::SampleAssembler::is_input(s)) {
    if (tag_t) last_tag_t_ = tag_t;
    ++stats_.ignored;
    return;
  }
  const std::optional<double> t = line_time(s.talker + f, tag_t);
  if (!t) {
    count("no time", "no TAG block with c: before it and no sentence rate (--nmea-rate)");
    return;
  }
  const nmea::InputResult r = assembler_->add_sentence(*t, s);
  switch (r.use) {
    case nmea::InputUse::kRefused:
      count(nmea::to_string(r.rejection.reason), f + ": " + r.rejection.text);
      return;
    case nmea::InputUse::kOutOfOrder:
      count("time going back", f + ": t = " + std::to_string(*t) + " before the latest line's");
      return;
    case nmea::InputUse::kNotValid:
      count("status V", f + ": its status says the data are not valid (or the value is empty)");
      break;
    case nmea::InputUse::kUsed:
      ++stats_.used;
      break;
    case nmea::InputUse::kNotAnInput:  // is_input said it is one
      return;
  }
  latest_t_ = *t;
}

NmeaSimWriter::NmeaSimWriter(std::ostream& out, const NmeaOutputOptions& options)
    : out_(out), options_(options) {}

void NmeaSimWriter::put(const std::string& sentence, double t) {
  nmea::TagBlock tag;
  tag.source = options_.source;
  line_count_ = line_count_ % 999 + 1;  // IEC 61162-450: 1..999
  tag.line_count = line_count_;
  tag.unix_time_ms = options_.epoch_ms + std::llround(t * 1000.0);
  const nmea::Result<std::string> block = nmea::format_tag_block(tag);
  if (!block)
    throw std::runtime_error("NMEA TAG block at t = " + std::to_string(t) + ": " +
                             block.rejection().text);
  out_ << block.value() << sentence;
}

void NmeaSimWriter::write(double t, double v, double r, double delta, double psi, double u) {
  auto emit = [&](const nmea::Result<std::string>& s, const char* what) {
    if (!s) {
      throw std::runtime_error(std::string("NMEA ") + what + " at t = " + std::to_string(t) + ": " +
                               s.rejection().text);
    }
    put(s.value(), t);
  };
  nmea::Rot rot;
  rot.rate_deg_per_min = field_value(r * kRadToDeg * 60.0, nmea::kMaxRateOfTurn, kNmeaDecimalsRot);
  rot.status = status_of(rot.rate_deg_per_min);
  emit(nmea::format_rot(rot), "ROT");

  // RSA > 0 turns the bow to starboard; delta has the sign of the model's B (b2 < 0: to port).
  const double rsa_deg =
      (nmea::rudder_sign_from_b2(options_.b2) == nmea::RudderSign::kPositiveToPort ? -delta
                                                                                   : delta) *
      kRadToDeg;
  nmea::Rsa rsa;
  rsa.starboard_deg = field_value(rsa_deg, nmea::kMaxRudderAngle, kNmeaDecimalsRudder);
  rsa.starboard_status = status_of(rsa.starboard_deg);
  emit(nmea::format_rsa(rsa), "RSA");

  constexpr double kKnotsPerMs = 1.0 / nmea::kMetresPerSecondPerKnot;
  nmea::Vbw vbw;
  const double surge = std::isfinite(u) ? u : options_.surge_speed;
  vbw.water_longitudinal_kn =
      field_value(surge * kKnotsPerMs, nmea::kMaxSpeedKnots, kNmeaDecimalsSpeed);
  vbw.water_transverse_kn = field_value(v * kKnotsPerMs, nmea::kMaxSpeedKnots, kNmeaDecimalsSpeed);
  vbw.water_status = status_of(vbw.water_transverse_kn);
  vbw.ground_status = nmea::Status::kInvalid;  // no ground speed from the simulator
  emit(nmea::format_vbw(vbw), "VBW");

  if (options_.heading && std::isfinite(psi)) {
    nmea::Hdt hdt;
    double deg = std::fmod(psi * kRadToDeg, 360.0);
    if (deg < 0.0) deg += 360.0;
    deg = round_to(deg, kNmeaDecimalsHeading);
    if (deg >= 360.0) deg = 0.0;
    hdt.heading_deg = deg;
    emit(nmea::format_hdt(hdt), "HDT");
  }
}

}  // namespace usvfdi::io
