#include "usv_fdi/io/csv.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <istream>
#include <ostream>
#include <set>
#include <utility>

namespace usvfdi::io {
namespace {

constexpr const char* kRequired[4] = {"t", "v", "r", "delta"};

/// Bytes read from the input at a time; the buffer holds one block beyond the longest line.
constexpr std::size_t kReadBlock = 4 * kCsvMaxLine;

std::string_view trim(std::string_view s) {
  std::size_t b = 0, e = s.size();
  while (b < e && (s[b] == ' ' || s[b] == '\t')) ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t')) --e;
  return s.substr(b, e - b);
}

/// The fields between commas, as views into `line`.
void split(std::string_view line, std::vector<std::string_view>* out) {
  out->clear();
  const char* p = line.data();
  const char* const end = p + line.size();
  while (true) {
    const void* comma = std::memchr(p, ',', static_cast<std::size_t>(end - p));
    if (comma == nullptr) {
      out->emplace_back(p, static_cast<std::size_t>(end - p));
      return;
    }
    const char* c = static_cast<const char*>(comma);
    out->emplace_back(p, static_cast<std::size_t>(c - p));
    p = c + 1;
  }
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& x : v) s += (s.empty() ? "" : ",") + x;
  return s;
}

std::string shorten(const std::string& s) { return s.size() > 120 ? s.substr(0, 117) + "..." : s; }

std::string format_message(const std::string& file, std::size_t line, const std::string& column,
                           const std::string& text, const std::string& reason) {
  std::string m = file;
  if (line > 0) m += ":" + std::to_string(line);
  m += ": ";
  if (!column.empty()) m += "column '" + column + "': ";
  m += reason;
  if (!text.empty() || !column.empty()) m += ": '" + shorten(text) + "'";
  return m;
}

/// parse_csv_number on a view. A plain decimal ([-]digits[.digits][e[+-]digits]) is read in
/// place by std::from_chars; everything else it does not read whole (a leading '+', hex
/// floats, inf, nan(...), other white space, a value out of range, a NUL) goes to strtod on a
/// NUL-terminated copy, so the field means exactly what it meant when strtod read them all
/// (both round to nearest, correctly).
bool parse_number(std::string_view field, double* out) {
  const std::string_view s = trim(field);
  if (s.empty() || s == "nan" || s == "NaN" || s == "NAN") {
    *out = kNaN;
    return true;
  }
  const char first = s[0] == '-' && s.size() > 1 ? s[1] : s[0];
  if ((first >= '0' && first <= '9') || first == '.') {
    double x = 0.0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
    if (ec == std::errc() && end == s.data() + s.size()) {
      *out = x;
      return true;
    }
  }
  const std::string copy(s);  // strtod stops at a NUL inside: what follows it is not read
  const char* begin = copy.c_str();
  char* end = nullptr;
  const double x = std::strtod(begin, &end);
  if (end == begin || *end != '\0') return false;
  *out = x;  // ERANGE: +-HUGE_VAL or a denormal, which the engine's validity checks judge
  return true;
}

}  // namespace

InputError::InputError(const std::string& file, std::size_t line, const std::string& column,
                       const std::string& text, const std::string& reason)
    : std::runtime_error(format_message(file, line, column, text, reason)),
      file_(file),
      line_(line),
      column_(column),
      text_(text) {}

bool parse_csv_number(const std::string& field, double* out) { return parse_number(field, out); }

CsvSampleReader::CsvSampleReader(const std::string& path) : name_(path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    throw InputError(path, 0, "", "", std::string("cannot read: ") + std::strerror(errno));
  }
  if (S_ISDIR(st.st_mode)) {
    throw InputError(path, 0, "", "", std::string("cannot read: ") + std::strerror(EISDIR));
  }
  auto f = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!*f) {
    throw InputError(path, 0, "", "", std::string("cannot open: ") + std::strerror(errno));
  }
  in_ = std::move(f);
  read_header();
}

CsvSampleReader::CsvSampleReader(std::unique_ptr<std::istream> in, const std::string& name)
    : in_(std::move(in)), name_(name) {
  read_header();
}

CsvSampleReader::~CsvSampleReader() = default;

bool CsvSampleReader::fill() {
  if (eof_) return false;
  std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
  end_ -= begin_;
  begin_ = 0;
  in_->read(buffer_.data() + end_, static_cast<std::streamsize>(buffer_.size() - end_));
  const std::size_t got = static_cast<std::size_t>(in_->gcount());
  end_ += got;
  if (!*in_) eof_ = true;  // end of the input (or a read error, told at its end)
  return got > 0;
}

bool CsvSampleReader::next_line(std::string_view* text) {
  // At most kLook bytes of a line are looked at, so that a file without line ends cannot take
  // the memory: kCsvMaxLine + 1 is "one byte too long", kCsvMaxLine + 2 "no line end in sight"
  // (the two messages of the getline reader before).
  constexpr std::size_t kLook = kCsvMaxLine + 2;
  while (true) {
    std::size_t avail = end_ - begin_;
    const void* nl = std::memchr(buffer_.data() + begin_, '\n', std::min(avail, kLook));
    while (nl == nullptr && avail < kLook && fill()) {
      nl = std::memchr(buffer_.data() + begin_ + avail, '\n',
                       std::min(end_ - begin_, kLook) - avail);
      avail = end_ - begin_;
    }
    if (nl == nullptr && avail == 0) break;  // end of the input
    const char* b = buffer_.data() + begin_;
    std::size_t n = nl != nullptr ? static_cast<std::size_t>(static_cast<const char*>(nl) - b)
                                  : std::min(avail, kLook);
    begin_ += nl != nullptr ? n + 1 : n;
    ++line_;
    if (n >= kLook) {
      throw InputError(name_, line_, "", "",
                       "line longer than " + std::to_string(kCsvMaxLine) +
                           " bytes (the limit; is this a CSV file with line ends?)");
    }
    if (n > kCsvMaxLine) {
      throw InputError(name_, line_, "", "",
                       "line longer than " + std::to_string(kCsvMaxLine) + " bytes (the limit)");
    }
    if (n > 0 && b[n - 1] == '\r') --n;
    if (line_ == 1 && n >= 3 && std::memcmp(b, "\xEF\xBB\xBF", 3) == 0) {
      b += 3;
      n -= 3;
    }
    if (std::memchr(b, '\0', n) != nullptr) {
      throw InputError(name_, line_, "", "",
                       "NUL byte in the line (a binary or UTF-16 file? expected ASCII/UTF-8 text)");
    }
    if (std::memchr(b, '\r', n) != nullptr) {
      throw InputError(name_, line_, "", "",
                       "carriage return inside a line: the file has CR-only line ends (convert "
                       "them to LF or CRLF)");
    }
    *text = std::string_view(b, n);
    const std::string_view t = trim(*text);
    if (t.empty() || t[0] == '#') continue;
    return true;
  }
  if (in_->bad()) {
    throw InputError(name_, line_ + 1, "", "", std::string("read error: ") + std::strerror(errno));
  }
  return false;
}

void CsvSampleReader::read_header() {
  buffer_.resize(kCsvMaxLine + 2 + kReadBlock);
  std::string_view line;
  if (!next_line(&line)) {
    throw InputError(name_, 0, "", "", "empty file (expected a header line naming t,v,r,delta)");
  }
  split(line, &fields_);
  if (fields_.size() > kCsvMaxColumns) {
    throw InputError(name_, line_, "", "",
                     "the header has " + std::to_string(fields_.size()) + " columns (at most " +
                         std::to_string(kCsvMaxColumns) + ")");
  }
  const std::string text(line);
  for (const std::string_view f : fields_) header_.emplace_back(trim(f));
  std::set<std::string> names;
  for (std::size_t i = 0; i < header_.size(); ++i) {
    if (!header_[i].empty() && !names.insert(header_[i]).second) {
      throw InputError(name_, line_, header_[i], text, "column named twice in the header");
    }
    for (int k = 0; k < 4; ++k) {
      if (header_[i] == kRequired[k]) col_[k] = static_cast<int>(i);
    }
    if (header_[i] == "u") col_u_ = static_cast<int>(i);
  }
  for (int k = 0; k < 4; ++k) {
    if (col_[k] < 0) {
      throw InputError(name_, line_, kRequired[k], text,
                       "required column missing from the header (need t,v,r,delta)");
    }
  }
}

bool CsvSampleReader::next(Sample* s) {
  std::string_view text;
  if (!next_line(&text)) return false;
  split(text, &fields_);
  if (fields_.size() != header_.size()) {
    throw InputError(name_, line_, "", std::string(text),
                     "expected " + std::to_string(header_.size()) + " fields (" + join(header_) +
                         "), got " + std::to_string(fields_.size()));
  }
  double x[4];
  for (int k = 0; k < 4; ++k) {
    const std::string_view f = fields_[static_cast<std::size_t>(col_[k])];
    if (!parse_number(f, &x[k])) {
      throw InputError(name_, line_, kRequired[k], std::string(f), "not a number");
    }
  }
  s->t = x[0];
  s->v = x[1];
  s->r = x[2];
  s->delta = x[3];
  s->u = kNaN;
  if (col_u_ >= 0) {
    const std::string_view f = fields_[static_cast<std::size_t>(col_u_)];
    if (!parse_number(f, &s->u))
      throw InputError(name_, line_, "u", std::string(f), "not a number");
  }
  ++rows_;
  return true;
}

SimCsvWriter::SimCsvWriter(std::ostream& out) : out_(out) {
  out_ << "t,v,r,delta,v_true,r_true,delta_true,psi,psi_ref,fault_a,fault_g\n";
}

void SimCsvWriter::write(const SimRow& row) {
  char buf[512];
  const auto kind = [](FaultKind k) { return k == FaultKind::kUnknown ? "" : to_string(k); };
  std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%s,%s\n",
                row.t, row.v, row.r, row.delta, row.v_true, row.r_true, row.delta_true, row.psi,
                row.psi_ref, kind(row.fault_a), kind(row.fault_g));
  out_ << buf;
}

}  // namespace usvfdi::io
