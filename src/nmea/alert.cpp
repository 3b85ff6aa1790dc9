// Bridge alert management sentences (include/usv_fdi/nmea/alert.hpp).
#include "usv_fdi/nmea/alert.hpp"

#include "fields.hpp"
#include "text.hpp"

namespace usvfdi::nmea {

namespace {

using fields::format_integer;
using fields::name;

constexpr long kMaxAlertId = 9999999;
constexpr long kMaxInstance = 999999;

std::optional<Rejection> required(const Sentence& s, std::size_t i, const char* what, long lo,
                                  long hi, long* out) {
  std::optional<long> v;
  if (auto bad = fields::integer(s, i, what, lo, hi, &v)) return bad;
  if (!v) return reject(Reason::kBadField, name(i, what) + ": missing");
  *out = *v;
  return std::nullopt;
}

std::optional<Rejection> required_int(const Sentence& s, std::size_t i, const char* what, long lo,
                                      long hi, int* out) {
  long v = 0;
  if (auto bad = required(s, i, what, lo, hi, &v)) return bad;
  *out = static_cast<int>(v);
  return std::nullopt;
}

bool all_digits(std::string_view t) {
  for (char c : t) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

std::optional<Rejection> read_time(const Sentence& s, std::size_t i, std::optional<UtcTime>* out) {
  out->reset();
  const std::string& t = s.fields.at(i);
  if (t.empty()) return std::nullopt;
  const std::string_view v = t;
  const bool shape = v.size() >= 6 && all_digits(v.substr(0, 6)) &&
                     (v.size() == 6 || (v[6] == '.' && v.size() > 7 && all_digits(v.substr(7))));
  if (!shape) {
    return reject(Reason::kBadField, name(i, "time") + ": '" + t + "' is not hhmmss.ss");
  }
  const auto two = [&v](std::size_t at) { return (v[at] - '0') * 10 + (v[at + 1] - '0'); };
  UtcTime u;
  u.hours = two(0);
  u.minutes = two(2);
  const int seconds = two(4);
  int hundredths = 0;
  if (v.size() > 7) hundredths += (v[7] - '0') * 10;
  if (v.size() > 8) hundredths += v[8] - '0';
  if (u.hours > 23 || u.minutes > 59 || seconds > 60) {
    return reject(Reason::kOutOfRange, name(i, "time") + ": '" + t + "' is not a time of day");
  }
  u.centiseconds = seconds * 100 + hundredths;
  *out = u;
  return std::nullopt;
}

std::string format_time(const std::optional<UtcTime>& time) {
  if (!time) return {};
  const auto two = [](int x) {
    return std::string(1, static_cast<char>('0' + x / 10 % 10)) + static_cast<char>('0' + x % 10);
  };
  std::string out = two(time->hours) + two(time->minutes) + two(time->centiseconds / 100);
  const int h = time->centiseconds % 100;
  if (h % 10 != 0) {
    out += "." + two(h);
  } else if (h != 0) {
    out += "." + std::string(1, static_cast<char>('0' + h / 10));
  }
  return out;
}

std::optional<Rejection> read_identity(const Sentence& s, std::size_t i, AlertIdentity* out) {
  const std::string& m = s.fields.at(i);
  bool mnemonic_ok = m.empty() || m.size() == 3;
  for (char c : m) mnemonic_ok = mnemonic_ok && ((c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9'));
  if (!mnemonic_ok) {
    return reject(Reason::kBadField, name(i, "manufacturer mnemonic") + ": '" + m +
                                         "' is not null or three characters A-Z, 0-9");
  }
  out->manufacturer = m;
  if (auto bad = required(s, i + 1, "alert identifier", 0, kMaxAlertId, &out->id)) return bad;
  return fields::integer(s, i + 2, "alert instance", 1, kMaxInstance, &out->instance);
}

void write_identity(const AlertIdentity& a, std::vector<std::string>* f) {
  f->push_back(a.manufacturer);
  f->push_back(std::to_string(a.id));
  f->push_back(format_integer(a.instance));
}

template <class Enum>
std::optional<Rejection> read_enum(const Sentence& s, std::size_t i, const char* what,
                                   std::string_view allowed, std::optional<Enum>* out) {
  char c = '\0';
  out->reset();
  if (auto bad = fields::letter(s, i, what, allowed, &c)) return bad;
  if (c != '\0') *out = static_cast<Enum>(c);
  return std::nullopt;
}

template <class Enum>
std::string write_enum(const std::optional<Enum>& e) {
  return e ? std::string(1, static_cast<char>(*e)) : std::string();
}

std::optional<Rejection> read_command(const Sentence& s, std::size_t i, const char* what,
                                      AlertCommand* out) {
  std::optional<AlertCommand> c;
  if (auto bad = read_enum(s, i, what, "AQOS", &c)) return bad;
  if (!c) return reject(Reason::kBadField, name(i, what) + ": missing");
  *out = *c;
  return std::nullopt;
}

/// Fields 1-5 of ARC and ACN: time, manufacturer mnemonic, alert identifier, instance, command.
std::optional<Rejection> read_alert_command(const Sentence& s, const char* what,
                                            std::optional<UtcTime>* time, AlertIdentity* alert,
                                            AlertCommand* command) {
  if (auto bad = read_time(s, 0, time)) return bad;
  if (auto bad = read_identity(s, 1, alert)) return bad;
  return read_command(s, 4, what, command);
}

std::vector<std::string> write_alert_command(const std::optional<UtcTime>& time,
                                             const AlertIdentity& alert, AlertCommand command) {
  std::vector<std::string> f{format_time(time)};
  write_identity(alert, &f);
  f.push_back(std::string(1, static_cast<char>(command)));
  return f;
}

bool needs_escape(char c) { return is_reserved(c) || c == ',' || c == '^'; }

/// The text as written in a field: '^hh' for reserved characters, ',' and '^'; '?' for a
/// non-printable one.
std::string encode_text(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (!is_printable(c)) {
      out += '?';
    } else if (needs_escape(c)) {
      out += '^';
      out += hex_byte(static_cast<unsigned char>(c));
    } else {
      out += c;
    }
  }
  return out;
}

std::optional<Rejection> decode_text(const Sentence& s, std::size_t i, std::string* out) {
  const std::string& raw = s.fields.at(i);
  out->clear();
  for (std::size_t j = 0; j < raw.size(); ++j) {
    if (raw[j] != '^') {
      *out += raw[j];
      continue;
    }
    int value = 0;
    if (j + 2 >= raw.size() || !parse_hex_byte(std::string_view(raw).substr(j + 1, 2), &value) ||
        !is_printable(static_cast<char>(value))) {
      return reject(Reason::kBadField, name(i, "alert text") +
                                           ": '^' not followed by the hex code of a printable "
                                           "character at " +
                                           std::to_string(j + 1));
    }
    *out += static_cast<char>(value);
    j += 2;
  }
  return std::nullopt;
}

}  // namespace

bool Alf::operator==(const Alf& o) const {
  return talker == o.talker && total_sentences == o.total_sentences &&
         sentence_number == o.sentence_number && message_id == o.message_id && time == o.time &&
         category == o.category && priority == o.priority && state == o.state && alert == o.alert &&
         revision == o.revision && escalation == o.escalation && text == o.text;
}

Result<Alf> parse_alf(const Sentence& s) {
  if (auto bad = fields::expect(s, "ALF", 13, 13)) return *bad;
  Alf x;
  x.talker = s.talker;
  if (auto bad = required_int(s, 0, "total sentences", 1, 2, &x.total_sentences)) return *bad;
  if (auto bad = required_int(s, 1, "sentence number", 1, x.total_sentences, &x.sentence_number)) {
    return *bad;
  }
  if (auto bad = required_int(s, 2, "message identifier", 0, 9, &x.message_id)) return *bad;
  if (auto bad = read_time(s, 3, &x.time)) return *bad;
  if (auto bad = read_enum(s, 4, "alert category", "ABC", &x.category)) return *bad;
  if (auto bad = read_enum(s, 5, "alert priority", "EAWC", &x.priority)) return *bad;
  if (auto bad = read_enum(s, 6, "alert state", "VSAOUN", &x.state)) return *bad;
  if (x.sentence_number == 1 && (!x.category || !x.priority || !x.state)) {
    return reject(Reason::kBadField,
                  "ALF sentence 1 without alert category, priority or state (fields 5-7)");
  }
  if (auto bad = read_identity(s, 7, &x.alert)) return *bad;
  if (auto bad = required_int(s, 10, "revision counter", 1, 99, &x.revision)) return *bad;
  std::optional<long> escalation;
  if (auto bad = fields::integer(s, 11, "escalation counter", 0, 9, &escalation)) return *bad;
  if (escalation) x.escalation = static_cast<int>(*escalation);
  if (auto bad = decode_text(s, 12, &x.text)) return *bad;
  return x;
}

Result<Alc> parse_alc(const Sentence& s) {
  if (auto bad = fields::expect(s, "ALC", 4, s.fields.size() < 4 ? 4 : s.fields.size())) {
    return *bad;
  }
  Alc x;
  x.talker = s.talker;
  if (auto bad = required_int(s, 0, "total sentences", 1, 99, &x.total_sentences)) return *bad;
  if (auto bad = required_int(s, 1, "sentence number", 1, x.total_sentences, &x.sentence_number)) {
    return *bad;
  }
  if (auto bad = required_int(s, 2, "message identifier", 0, 99, &x.message_id)) return *bad;
  long n = 0;
  if (auto bad = required(s, 3, "number of alert entries", 0, 99, &n)) return *bad;
  if (s.fields.size() != 4 + 4 * static_cast<std::size_t>(n)) {
    return reject(Reason::kFieldCount, "ALC with " + std::to_string(n) + " alert entries and " +
                                           std::to_string(s.fields.size()) + " fields (" +
                                           std::to_string(4 + 4 * n) + " expected)");
  }
  for (long k = 0; k < n; ++k) {
    AlcEntry e;
    const std::size_t at = 4 + 4 * static_cast<std::size_t>(k);
    if (auto bad = read_identity(s, at, &e.alert)) return *bad;
    if (auto bad = required_int(s, at + 3, "revision counter", 1, 99, &e.revision)) return *bad;
    x.entries.push_back(e);
  }
  return x;
}

Result<Hbt> parse_hbt(const Sentence& s) {
  if (auto bad = fields::expect(s, "HBT", 3, 3)) return *bad;
  Hbt x;
  x.talker = s.talker;
  if (auto bad = fields::number_in(s, 0, "repeat interval", 0.0, 999.0, &x.interval_s)) {
    return *bad;
  }
  char status = '\0';
  if (auto bad = fields::letter(s, 1, "equipment status", "AV", &status)) return *bad;
  if (status == '\0') return reject(Reason::kBadField, name(1, "equipment status") + ": missing");
  x.normal = status == 'A';
  if (auto bad = required_int(s, 2, "sequence identifier", 0, 9, &x.sequence)) return *bad;
  return x;
}

Result<Arc> parse_arc(const Sentence& s) {
  if (auto bad = fields::expect(s, "ARC", 5, 5)) return *bad;
  Arc x;
  x.talker = s.talker;
  if (auto bad = read_alert_command(s, "refused command", &x.time, &x.alert, &x.refused)) {
    return *bad;
  }
  return x;
}

Result<Acn> parse_acn(const Sentence& s) {
  if (auto bad = fields::expect(s, "ACN", 6, 6)) return *bad;
  Acn x;
  x.talker = s.talker;
  if (auto bad = read_alert_command(s, "alert command", &x.time, &x.alert, &x.command)) {
    return *bad;
  }
  if (s.fields[5] != "C") {
    return reject(Reason::kBadField, name(5, "sentence status flag") + ": '" + s.fields[5] +
                                         "' is not C: not a command");
  }
  return x;
}

Sentence to_sentence(const Alf& x) {
  Sentence s = fields::make_sentence(x.talker, "ALF");
  s.fields = {std::to_string(x.total_sentences),
              std::to_string(x.sentence_number),
              std::to_string(x.message_id),
              format_time(x.time),
              write_enum(x.category),
              write_enum(x.priority),
              write_enum(x.state)};
  write_identity(x.alert, &s.fields);
  s.fields.push_back(std::to_string(x.revision));
  s.fields.push_back(x.escalation ? std::to_string(*x.escalation) : std::string());
  s.fields.push_back(encode_text(x.text));
  return s;
}

Sentence to_sentence(const Alc& x) {
  Sentence s = fields::make_sentence(x.talker, "ALC");
  s.fields = {std::to_string(x.total_sentences), std::to_string(x.sentence_number),
              std::to_string(x.message_id), std::to_string(x.entries.size())};
  for (const auto& e : x.entries) {
    write_identity(e.alert, &s.fields);
    s.fields.push_back(std::to_string(e.revision));
  }
  return s;
}

Sentence to_sentence(const Hbt& x) {
  Sentence s = fields::make_sentence(x.talker, "HBT");
  s.fields = {fields::format_number(x.interval_s), x.normal ? "A" : "V",
              std::to_string(x.sequence)};
  return s;
}

Sentence to_sentence(const Arc& x) {
  Sentence s = fields::make_sentence(x.talker, "ARC");
  s.fields = write_alert_command(x.time, x.alert, x.refused);
  return s;
}

Sentence to_sentence(const Acn& x) {
  Sentence s = fields::make_sentence(x.talker, "ACN");
  s.fields = write_alert_command(x.time, x.alert, x.command);
  s.fields.push_back("C");
  return s;
}

Result<std::string> format_alf(const Alf& x) {
  Alf fitted = x;
  fitted.text.clear();
  auto empty = format_sentence(to_sentence(fitted));
  if (!empty) return empty.rejection();
  std::size_t budget = kMaxSentenceLength - empty.value().size();
  for (char c : x.text) {
    const std::size_t cost = is_printable(c) && needs_escape(c) ? 3 : 1;
    if (cost > budget) break;
    budget -= cost;
    fitted.text += is_printable(c) ? c : '?';
  }
  return fields::format_checked(fitted, parse_alf);
}

Result<std::vector<std::string>> format_alf_message(const Alf& alert,
                                                    const std::string& description) {
  Alf title = alert;
  title.total_sentences = description.empty() ? 1 : 2;
  title.sentence_number = 1;
  auto first = format_alf(title);
  if (!first) return first.rejection();
  std::vector<std::string> out{first.value()};
  if (description.empty()) return out;
  Alf second = title;
  second.sentence_number = 2;
  second.time.reset();
  second.category.reset();
  second.priority.reset();
  second.state.reset();
  second.text = description;
  auto more = format_alf(second);
  if (!more) return more.rejection();
  out.push_back(more.value());
  return out;
}

Result<std::string> format_alc(const Alc& x) { return fields::format_checked(x, parse_alc); }
Result<std::string> format_hbt(const Hbt& x) { return fields::format_checked(x, parse_hbt); }
Result<std::string> format_arc(const Arc& x) { return fields::format_checked(x, parse_arc); }
Result<std::string> format_acn(const Acn& x) { return fields::format_checked(x, parse_acn); }

Result<std::vector<std::string>> format_alc_list(const std::string& talker, int message_id,
                                                 const std::vector<AlcEntry>& entries) {
  // Pack with two-digit totals (the longest), then number the sentences.
  std::vector<Alc> parts(1);
  parts[0].talker = talker;
  for (const auto& e : entries) {
    Alc trial = parts.back();
    trial.entries.push_back(e);
    trial.total_sentences = trial.sentence_number = trial.message_id = 99;  // widest
    auto fits = format_alc(trial);
    if (!fits && fits.rejection().reason != Reason::kTooLong) return fits.rejection();
    if (!fits && parts.back().entries.empty()) return fits.rejection();
    if (!fits) {
      parts.emplace_back();
      parts.back().talker = talker;
    }
    parts.back().entries.push_back(e);
  }
  if (parts.size() > 99) return reject(Reason::kTooLong, "ALC list of more than 99 sentences");
  std::vector<std::string> out;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    parts[k].total_sentences = static_cast<int>(parts.size());
    parts[k].sentence_number = static_cast<int>(k + 1);
    parts[k].message_id = message_id;
    auto text = format_alc(parts[k]);
    if (!text) return text.rejection();
    out.push_back(text.value());
  }
  return out;
}

}  // namespace usvfdi::nmea
