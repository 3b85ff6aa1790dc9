#include "usv_fdi/io/csv.hpp"

#include <sys/stat.h>

#include <cerrno>
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

std::string trim(const std::string& s) {
  std::size_t b = 0, e = s.size();
  while (b < e && (s[b] == ' ' || s[b] == '\t')) ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t')) --e;
  return s.substr(b, e - b);
}

void split(const std::string& line, std::vector<std::string>* out) {
  out->clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string::npos) {
      out->push_back(line.substr(start));
      return;
    }
    out->push_back(line.substr(start, comma - start));
    start = comma + 1;
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

}  // namespace

InputError::InputError(const std::string& file, std::size_t line, const std::string& column,
                       const std::string& text, const std::string& reason)
    : std::runtime_error(format_message(file, line, column, text, reason)),
      file_(file),
      line_(line),
      column_(column),
      text_(text) {}

bool parse_csv_number(const std::string& field, double* out) {
  const std::string s = trim(field);
  if (s.empty() || s == "nan" || s == "NaN" || s == "NAN") {
    *out = std::nan("");
    return true;
  }
  const char* begin = s.c_str();
  char* end = nullptr;
  errno = 0;
  const double x = std::strtod(begin, &end);
  if (end == begin || *end != '\0') return false;
  *out = x;  // ERANGE: +-HUGE_VAL or a denormal, which the engine's validity checks judge
  return true;
}

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

bool CsvSampleReader::next_line(std::string* text) {
  if (buffer_.empty()) buffer_.resize(kCsvMaxLine + 2);
  while (true) {
    // At most kCsvMaxLine + 1 bytes (the + 1 tells a line that is too long), so that a file
    // without line ends cannot take the memory.
    in_->getline(buffer_.data(), static_cast<std::streamsize>(kCsvMaxLine + 2));
    const std::size_t got = static_cast<std::size_t>(in_->gcount());
    if (got == 0 && in_->fail()) break;  // end of file
    ++line_;
    if (in_->fail() && !in_->eof()) {
      throw InputError(name_, line_, "", "",
                       "line longer than " + std::to_string(kCsvMaxLine) +
                           " bytes (the limit; is this a CSV file with line ends?)");
    }
    // gcount includes the '\n' when there was one (not at the end of the file).
    text->assign(buffer_.data(), in_->eof() ? got : got - 1);
    if (in_->eof()) in_->clear(std::ios::eofbit);
    if (text->size() > kCsvMaxLine) {
      throw InputError(name_, line_, "", "",
                       "line longer than " + std::to_string(kCsvMaxLine) + " bytes (the limit)");
    }
    if (!text->empty() && text->back() == '\r') text->pop_back();
    if (line_ == 1 && text->compare(0, 3, "\xEF\xBB\xBF") == 0) text->erase(0, 3);
    if (text->find('\0') != std::string::npos) {
      throw InputError(name_, line_, "", "",
                       "NUL byte in the line (a binary or UTF-16 file? expected ASCII/UTF-8 text)");
    }
    if (text->find('\r') != std::string::npos) {
      throw InputError(name_, line_, "", "",
                       "carriage return inside a line: the file has CR-only line ends (convert "
                       "them to LF or CRLF)");
    }
    const std::string t = trim(*text);
    if (t.empty() || t[0] == '#') continue;
    return true;
  }
  if (in_->bad()) {
    throw InputError(name_, line_ + 1, "", "", std::string("read error: ") + std::strerror(errno));
  }
  return false;
}

void CsvSampleReader::read_header() {
  std::string text;
  if (!next_line(&text)) {
    throw InputError(name_, 0, "", "", "empty file (expected a header line naming t,v,r,delta)");
  }
  split(text, &header_);
  if (header_.size() > kCsvMaxColumns) {
    throw InputError(name_, line_, "", "",
                     "the header has " + std::to_string(header_.size()) + " columns (at most " +
                         std::to_string(kCsvMaxColumns) + ")");
  }
  for (std::string& h : header_) h = trim(h);
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
  std::string text;
  if (!next_line(&text)) return false;
  split(text, &fields_);
  if (fields_.size() != header_.size()) {
    throw InputError(name_, line_, "", text,
                     "expected " + std::to_string(header_.size()) + " fields (" + join(header_) +
                         "), got " + std::to_string(fields_.size()));
  }
  double x[4];
  for (int k = 0; k < 4; ++k) {
    const std::string& f = fields_[static_cast<std::size_t>(col_[k])];
    if (!parse_csv_number(f, &x[k])) {
      throw InputError(name_, line_, kRequired[k], f, "not a number");
    }
  }
  s->t = x[0];
  s->v = x[1];
  s->r = x[2];
  s->delta = x[3];
  s->u = kNaN;
  if (col_u_ >= 0) {
    const std::string& f = fields_[static_cast<std::size_t>(col_u_)];
    if (!parse_csv_number(f, &s->u)) throw InputError(name_, line_, "u", f, "not a number");
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
