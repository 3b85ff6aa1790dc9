// Sensor channels, quantisation, sensor presets and settings, and the scripted faults.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#include "voyage_internal.hpp"

namespace usvfdi::sim {
namespace {
constexpr double kPi = 3.14159265358979323846;

bool parse_value(const std::string& text, double* out) {
  std::string t = text;
  double unit = 1.0;
  if (t.size() > 3 && t.compare(t.size() - 3, 3, "deg") == 0) {
    unit = kPi / 180.0;
    t.resize(t.size() - 3);
  }
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  if (t.empty() || end != t.c_str() + t.size() || !std::isfinite(v)) return false;
  *out = v * unit;
  return true;
}

ChannelNoise* channel_of(const std::string& name, SensorConfig* s) {
  if (name == "v" || name == "acc" || name == "accelerometer") return &s->v;
  if (name == "r" || name == "gyro") return &s->r;
  if (name == "delta" || name == "rudder") return &s->delta;
  return nullptr;
}

bool set_channel(ChannelNoise* c, const std::string& field, double v, std::string* why) {
  const bool nonneg = v >= 0;
  if (field == "white" && nonneg)
    c->white = v;
  else if (field == "gm" && nonneg)
    c->gm_sigma = v;
  else if (field == "gm_tau" && v > 0)
    c->gm_tau = v;
  else if (field == "bias_rw" && nonneg)
    c->bias_rw = v;
  else if (field == "bias")
    c->bias = v;
  else if (field == "lag" && nonneg)
    c->lag = v;
  else if (field == "step" && nonneg)
    c->quantiser.step = v;
  else if (field == "digits" && nonneg && v <= 17 && v == std::floor(v))
    c->quantiser.digits = static_cast<int>(v);
  else {
    *why =
        "unknown field or value out of range (fields: white, gm, gm_tau, bias_rw, bias, "
        "lag, step, digits; only bias may be negative, gm_tau > 0, digits 0..17)";
    return false;
  }
  return true;
}

bool set_global(const std::string& key, double v, SensorConfig* s, std::string* why) {
  if (key == "jitter" && v >= 0)
    s->jitter = v;
  else if ((key == "drop") && v >= 0 && v < 1)
    s->drop = v;
  else if ((key == "duplicate" || key == "dup") && v >= 0 && v < 1)
    s->duplicate = v;
  else if (key == "compass" && v >= 0)
    s->compass_sigma = v;
  else if (key == "compass_tau" && v >= 0)
    s->compass_tau = v;
  else {
    *why =
        "unknown key or value out of range (keys: jitter, drop, duplicate, compass, "
        "compass_tau, rot=nmea, <channel>.<field> with channel acc|gyro|rudder)";
    return false;
  }
  return true;
}
}  // namespace

double Quantiser::apply(double x) const {
  if (!std::isfinite(x)) return x;
  if (step > 0) x = std::round(x / step) * step;
  if (digits > 0 && x != 0.0) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*e", digits - 1, x);
    x = std::strtod(buf, nullptr);
  }
  return x;
}

bool sensor_preset(const std::string& name, double sigma_v, double sigma_r, SensorConfig* out) {
  SensorConfig s;
  s.v.white = sigma_v;
  s.r.white = sigma_r;
  if (name == "mems") {
    s.v.gm_sigma = 0.5 * sigma_v;
    s.r.gm_sigma = 0.5 * sigma_r;
    s.r.bias_rw = 1e-5;  // MEMS-grade bias instability: ~0.25 mrad/s after 10 minutes
    s.r.quantiser.step = kRotQuantum;
    s.v.quantiser.digits = 3;
    s.delta.quantiser.step = kRudderQuantum;
    s.delta.bias = 0.5 * kPi / 180.0;
    s.delta.lag = 0.2;
    s.compass_sigma = 0.2 * kPi / 180.0;
    s.jitter = 0.002;
    s.drop = 0.005;
    s.duplicate = 0.002;
  } else if (name != "ideal") {
    return false;
  }
  *out = s;
  return true;
}

bool apply_sensor_setting(const std::string& setting, SensorConfig* out, std::string* error) {
  const auto eq = setting.find('=');
  const std::string key = setting.substr(0, eq);
  const std::string value = eq == std::string::npos ? "" : setting.substr(eq + 1);
  const auto fail = [&](const std::string& why) {
    *error = "'" + setting + "': " + why;
    return false;
  };
  if (eq == std::string::npos) return fail("expected key=value (or a preset: ideal, mems)");
  if (key == "rot") {
    if (value != "nmea") return fail("rot takes 'nmea' (0.1 deg/min)");
    out->r.quantiser.step = kRotQuantum;
    return true;
  }
  double v = 0.0;
  if (!parse_value(value, &v)) return fail("not a number: '" + value + "'");
  std::string why;
  const auto dot = key.find('.');
  if (dot == std::string::npos) return set_global(key, v, out, &why) || fail(why);
  ChannelNoise* c = channel_of(key.substr(0, dot), out);
  if (c == nullptr) return fail("unknown channel '" + key.substr(0, dot) + "' (acc, gyro, rudder)");
  return set_channel(c, key.substr(dot + 1), v, &why) || fail(why);
}

double channel_sigma(const VoyageConfig& cfg, Sensor sensor) {
  const bool acc = sensor == Sensor::kAccelerometer;
  const double given = acc ? cfg.sigma_v : cfg.sigma_r;
  if (given > 0) return given;
  return acc ? cfg.sensors.v.white : cfg.sensors.r.white;
}

FaultInjection sigma_fault(const VoyageConfig& cfg, Sensor sensor, FaultKind kind, double t_start,
                           double t_end, double k_sigma, double spike_rate) {
  FaultInjection f;
  f.sensor = sensor;
  f.kind = kind;
  f.t_start = t_start;
  f.t_end = t_end;
  f.spike_rate = spike_rate;
  const bool in_sigma = kind == FaultKind::kBias || kind == FaultKind::kDrift ||
                        kind == FaultKind::kNoise || kind == FaultKind::kSpikes;
  f.magnitude = in_sigma ? k_sigma * channel_sigma(cfg, sensor) : k_sigma;
  return f;
}

std::vector<FaultInjection> standard_faults(const VoyageConfig& cfg, double t0, double length,
                                            double gap) {
  struct Kind {
    FaultKind kind;
    double k;
  };
  const Kind kinds[] = {{FaultKind::kBias, 10.0},         {FaultKind::kStuck, 0.0},
                        {FaultKind::kDrift, 10.0 / 30.0}, {FaultKind::kNoise, std::sqrt(63.0)},
                        {FaultKind::kScale, 0.5},         {FaultKind::kSpikes, 25.0},
                        {FaultKind::kStale, 0.0},         {FaultKind::kInvalid, 0.0}};
  std::vector<FaultInjection> out;
  double t = t0;
  for (int i = 0; t + length <= cfg.duration; ++i, t += length + gap) {
    const Kind& k = kinds[i % 8];
    const int cycle = i / 8;
    const Sensor s = (i + cycle) % 2 == 0 ? Sensor::kAccelerometer : Sensor::kGyro;
    out.push_back(sigma_fault(cfg, s, k.kind, t, t + length, k.k));
  }
  return out;
}

namespace detail {

Channel::Channel(const ChannelNoise& c, double dt, std::uint64_t seed, std::uint64_t id)
    : c_(c), dt_(dt), s_(seed, id), gm_(c.gm_sigma, c.gm_tau, dt) {
  gm_.start(&s_);
}

double Channel::measure(double truth) {
  if (first_ || !(c_.lag > 0)) {
    lagged_ = truth;
  } else {
    lagged_ += (truth - lagged_) * -std::expm1(-dt_ / c_.lag);
  }
  if (!first_ && c_.bias_rw > 0) walk_ += c_.bias_rw * std::sqrt(dt_) * s_.normal();
  first_ = false;
  const double white = c_.white > 0 ? c_.white * s_.normal() : 0.0;
  return lagged_ + c_.bias + walk_ + white + gm_.step(&s_);
}

Faults::Faults(const std::vector<FaultInjection>& faults, double dt, std::uint64_t seed)
    : f_(faults), held_(faults.size(), kNaN), dt_(dt), s_(seed, 20) {}

double Faults::apply(Sensor sensor, double t, double truth, double y, FaultKind* active) {
  *active = FaultKind::kUnknown;
  for (std::size_t i = 0; i < f_.size(); ++i) {
    if (f_[i].sensor != sensor) continue;
    if (t < f_[i].t_start || t >= f_[i].t_end) {
      held_[i] = kNaN;
      continue;
    }
    *active = f_[i].kind;
    y = apply_one(i, t, truth, y);
  }
  return y;
}

double Faults::apply_one(std::size_t i, double t, double truth, double y) {
  const FaultInjection& f = f_[i];
  switch (f.kind) {
    case FaultKind::kBias:
      return y + f.magnitude;
    case FaultKind::kDrift:
      return y + f.magnitude * (t - f.t_start);
    case FaultKind::kNoise:
      return y + f.magnitude * s_.normal();
    case FaultKind::kSpikes: {
      const bool spike = s_.uniform() < f.spike_rate * dt_;
      const double sign = s_.uniform() < 0.5 ? -1.0 : 1.0;
      return spike ? y + sign * f.magnitude : y;
    }
    case FaultKind::kScale:
      return y + f.magnitude * truth;
    case FaultKind::kStuck:
      if (std::isnan(held_[i])) held_[i] = y;
      return held_[i];
    case FaultKind::kStale:
      return kNaN;
    case FaultKind::kInvalid:
      return std::numeric_limits<double>::infinity();
    case FaultKind::kUnknown:
      break;
  }
  return y;
}

}  // namespace detail
}  // namespace usvfdi::sim
