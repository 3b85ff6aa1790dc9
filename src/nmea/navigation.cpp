// Typed navigation sentences (include/usv_fdi/nmea/navigation.hpp).
#include "usv_fdi/nmea/navigation.hpp"

#include "fields.hpp"

namespace usvfdi::nmea {

namespace {

using fields::format_letter;
using fields::format_number;

std::optional<Rejection> status(const Sentence& s, std::size_t i, const char* what, Status* out) {
  char c = '\0';
  if (auto bad = fields::letter(s, i, what, "AV", &c)) return bad;
  *out = static_cast<Status>(c);
  return std::nullopt;
}

std::optional<Rejection> speed(const Sentence& s, std::size_t i, const char* what,
                               std::optional<double>* out) {
  return fields::number(s, i, what, kMaxSpeedKnots, out);
}

std::optional<Rejection> heading(const Sentence& s, std::size_t i, const char* what,
                                 std::optional<double>* out) {
  return fields::number_in(s, i, what, 0.0, 360.0, out);
}

}  // namespace

bool Vbw::operator==(const Vbw& o) const {
  return talker == o.talker && water_longitudinal_kn == o.water_longitudinal_kn &&
         water_transverse_kn == o.water_transverse_kn && water_status == o.water_status &&
         ground_longitudinal_kn == o.ground_longitudinal_kn &&
         ground_transverse_kn == o.ground_transverse_kn && ground_status == o.ground_status &&
         stern_water_transverse_kn == o.stern_water_transverse_kn &&
         stern_water_status == o.stern_water_status &&
         stern_ground_transverse_kn == o.stern_ground_transverse_kn &&
         stern_ground_status == o.stern_ground_status;
}

Result<Rot> parse_rot(const Sentence& s) {
  if (auto bad = fields::expect(s, "ROT", 2, 2)) return *bad;
  Rot x;
  x.talker = s.talker;
  if (auto bad = fields::number(s, 0, "rate of turn", kMaxRateOfTurn, &x.rate_deg_per_min)) {
    return *bad;
  }
  if (auto bad = status(s, 1, "status", &x.status)) return *bad;
  return x;
}

Result<Rsa> parse_rsa(const Sentence& s) {
  if (auto bad = fields::expect(s, "RSA", 4, 4)) return *bad;
  Rsa x;
  x.talker = s.talker;
  if (auto bad = fields::number(s, 0, "starboard rudder", kMaxRudderAngle, &x.starboard_deg)) {
    return *bad;
  }
  if (auto bad = status(s, 1, "starboard status", &x.starboard_status)) return *bad;
  if (auto bad = fields::number(s, 2, "port rudder", kMaxRudderAngle, &x.port_deg)) return *bad;
  if (auto bad = status(s, 3, "port status", &x.port_status)) return *bad;
  return x;
}

Result<Hdt> parse_hdt(const Sentence& s) {
  if (auto bad = fields::expect(s, "HDT", 2, 2)) return *bad;
  Hdt x;
  x.talker = s.talker;
  if (auto bad = heading(s, 0, "heading", &x.heading_deg)) return *bad;
  if (auto bad = fields::unit(s, 1, "true", "T")) return *bad;
  return x;
}

Result<Ths> parse_ths(const Sentence& s) {
  if (auto bad = fields::expect(s, "THS", 2, 2)) return *bad;
  Ths x;
  x.talker = s.talker;
  if (auto bad = heading(s, 0, "heading", &x.heading_deg)) return *bad;
  char c = '\0';
  if (auto bad = fields::letter(s, 1, "mode", "AEMSV", &c)) return *bad;
  x.mode = static_cast<HeadingMode>(c);
  return x;
}

Result<Vbw> parse_vbw(const Sentence& s) {
  if (auto bad = fields::expect(s, "VBW", 6, 10)) return *bad;
  if (s.fields.size() != 6 && s.fields.size() != 10) {
    return reject(Reason::kFieldCount,
                  "VBW with " + std::to_string(s.fields.size()) + " fields (6 or 10 expected)");
  }
  Vbw x;
  x.talker = s.talker;
  if (auto bad = speed(s, 0, "longitudinal water speed", &x.water_longitudinal_kn)) return *bad;
  if (auto bad = speed(s, 1, "transverse water speed", &x.water_transverse_kn)) return *bad;
  if (auto bad = status(s, 2, "water speed status", &x.water_status)) return *bad;
  if (auto bad = speed(s, 3, "longitudinal ground speed", &x.ground_longitudinal_kn)) return *bad;
  if (auto bad = speed(s, 4, "transverse ground speed", &x.ground_transverse_kn)) return *bad;
  if (auto bad = status(s, 5, "ground speed status", &x.ground_status)) return *bad;
  if (s.fields.size() == 10) {
    if (auto bad = speed(s, 6, "stern transverse water speed", &x.stern_water_transverse_kn)) {
      return *bad;
    }
    if (auto bad = status(s, 7, "stern water speed status", &x.stern_water_status)) return *bad;
    if (auto bad = speed(s, 8, "stern transverse ground speed", &x.stern_ground_transverse_kn)) {
      return *bad;
    }
    if (auto bad = status(s, 9, "stern ground speed status", &x.stern_ground_status)) {
      return *bad;
    }
  }
  return x;
}

Result<Vtg> parse_vtg(const Sentence& s) {
  if (auto bad = fields::expect(s, "VTG", 8, 9)) return *bad;
  Vtg x;
  x.talker = s.talker;
  if (auto bad = heading(s, 0, "course over ground, true", &x.course_true_deg)) return *bad;
  if (auto bad = fields::unit(s, 1, "true", "T")) return *bad;
  if (auto bad = heading(s, 2, "course over ground, magnetic", &x.course_magnetic_deg)) {
    return *bad;
  }
  if (auto bad = fields::unit(s, 3, "magnetic", "M")) return *bad;
  if (auto bad =
          fields::number_in(s, 4, "speed over ground, knots", 0.0, kMaxSpeedKnots, &x.speed_kn)) {
    return *bad;
  }
  if (auto bad = fields::unit(s, 5, "knots", "N")) return *bad;
  if (auto bad = fields::number_in(s, 6, "speed over ground, km/h", 0.0,
                                   kMaxSpeedKnots * kKmPerNauticalMile, &x.speed_kmh)) {
    return *bad;
  }
  if (auto bad = fields::unit(s, 7, "km/h", "K")) return *bad;
  if (s.fields.size() == 9) {
    char c = '\0';
    if (auto bad = fields::letter(s, 8, "mode", "ADEMSNP", &c)) return *bad;
    x.mode = static_cast<PositioningMode>(c);
  }
  return x;
}

Sentence to_sentence(const Rot& x) {
  Sentence s = fields::make_sentence(x.talker, "ROT");
  s.fields = {format_number(x.rate_deg_per_min), format_letter(x.status)};
  return s;
}

Sentence to_sentence(const Rsa& x) {
  Sentence s = fields::make_sentence(x.talker, "RSA");
  s.fields = {format_number(x.starboard_deg), format_letter(x.starboard_status),
              format_number(x.port_deg), format_letter(x.port_status)};
  return s;
}

Sentence to_sentence(const Hdt& x) {
  Sentence s = fields::make_sentence(x.talker, "HDT");
  s.fields = {format_number(x.heading_deg), "T"};
  return s;
}

Sentence to_sentence(const Ths& x) {
  Sentence s = fields::make_sentence(x.talker, "THS");
  s.fields = {format_number(x.heading_deg), format_letter(x.mode)};
  return s;
}

Sentence to_sentence(const Vbw& x) {
  Sentence s = fields::make_sentence(x.talker, "VBW");
  s.fields = {format_number(x.water_longitudinal_kn), format_number(x.water_transverse_kn),
              format_letter(x.water_status),          format_number(x.ground_longitudinal_kn),
              format_number(x.ground_transverse_kn),  format_letter(x.ground_status)};
  if (x.has_stern()) {
    s.fields.push_back(format_number(x.stern_water_transverse_kn));
    s.fields.push_back(format_letter(x.stern_water_status));
    s.fields.push_back(format_number(x.stern_ground_transverse_kn));
    s.fields.push_back(format_letter(x.stern_ground_status));
  }
  return s;
}

Sentence to_sentence(const Vtg& x) {
  Sentence s = fields::make_sentence(x.talker, "VTG");
  s.fields = {format_number(x.course_true_deg), "T", format_number(x.course_magnetic_deg), "M",
              format_number(x.speed_kn),        "N", format_number(x.speed_kmh),           "K"};
  if (x.mode != PositioningMode::kAbsent) s.fields.push_back(format_letter(x.mode));
  return s;
}

Result<std::string> format_rot(const Rot& x) { return fields::format_checked(x, parse_rot); }
Result<std::string> format_rsa(const Rsa& x) { return fields::format_checked(x, parse_rsa); }
Result<std::string> format_hdt(const Hdt& x) { return fields::format_checked(x, parse_hdt); }
Result<std::string> format_ths(const Ths& x) { return fields::format_checked(x, parse_ths); }
Result<std::string> format_vbw(const Vbw& x) { return fields::format_checked(x, parse_vbw); }
Result<std::string> format_vtg(const Vtg& x) { return fields::format_checked(x, parse_vtg); }

}  // namespace usvfdi::nmea
