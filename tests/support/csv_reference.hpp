// The CSV sample reader as it was before it parsed in place (src/io/csv.cpp at cb01cc4: getline
// into a string, a std::string per field, strtod), kept only as a reference: tests/io checks the
// in-place reader against it input by input (rows, values, errors and messages), and
// bench/csv_bench.cpp measures both side by side. Not used by any program. Its messages repeat
// the reader's on purpose: they are what the reader must keep byte-identical. A change of the
// reader's behaviour made on purpose changes this copy too (or retires it), in the same commit.
#pragma once

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <istream>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "usv_fdi/core/types.hpp"
#include "usv_fdi/io/csv.hpp"

namespace usvfdi::reference {

inline std::string trim(const std::string& s) {
  std::size_t b = 0, e = s.size();
  while (b < e && (s[b] == ' ' || s[b] == '\t')) ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t')) --e;
  return s.substr(b, e - b);
}

/// parse_csv_number as it was: trim, the NaN spellings, then strtod on the C string.
inline bool parse_csv_number(const std::string& field, double* out) {
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
  *out = x;
  return true;
}

/// io::CsvSampleReader as it was (stream constructor only).
class CsvSampleReader {
 public:
  CsvSampleReader(std::unique_ptr<std::istream> in, const std::string& name)
      : in_(std::move(in)), name_(name) {
    read_header();
  }

  bool next(Sample* s) {
    std::string text;
    if (!next_line(&text)) return false;
    split(text, &fields_);
    if (fields_.size() != header_.size()) {
      std::string joined;
      for (const std::string& h : header_) joined += (joined.empty() ? "" : ",") + h;
      throw io::InputError(name_, line_, "", text,
                           "expected " + std::to_string(header_.size()) + " fields (" + joined +
                               "), got " + std::to_string(fields_.size()));
    }
    double x[4];
    for (int k = 0; k < 4; ++k) {
      const std::string& f = fields_[static_cast<std::size_t>(col_[k])];
      if (!parse_csv_number(f, &x[k])) throw io::InputError(name_, line_, kRequired[k], f, kNaN_);
    }
    s->t = x[0];
    s->v = x[1];
    s->r = x[2];
    s->delta = x[3];
    s->u = kNaN;
    if (col_u_ >= 0) {
      const std::string& f = fields_[static_cast<std::size_t>(col_u_)];
      if (!parse_csv_number(f, &s->u)) throw io::InputError(name_, line_, "u", f, kNaN_);
    }
    ++rows_;
    return true;
  }

  std::size_t line() const { return line_; }
  std::size_t rows() const { return rows_; }
  const std::vector<std::string>& header() const { return header_; }

 private:
  static constexpr const char* kRequired[4] = {"t", "v", "r", "delta"};
  static constexpr const char* kNaN_ = "not a number";

  static void split(const std::string& line, std::vector<std::string>* out) {
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

  bool next_line(std::string* text) {
    constexpr std::size_t kMax = io::kCsvMaxLine;
    if (buffer_.empty()) buffer_.resize(kMax + 2);
    while (true) {
      in_->getline(buffer_.data(), static_cast<std::streamsize>(kMax + 2));
      const std::size_t got = static_cast<std::size_t>(in_->gcount());
      if (got == 0 && in_->fail()) break;
      ++line_;
      if (in_->fail() && !in_->eof()) {
        throw io::InputError(name_, line_, "", "",
                             "line longer than " + std::to_string(kMax) +
                                 " bytes (the limit; is this a CSV file with line ends?)");
      }
      text->assign(buffer_.data(), in_->eof() ? got : got - 1);
      if (in_->eof()) in_->clear(std::ios::eofbit);
      if (text->size() > kMax) {
        throw io::InputError(name_, line_, "", "",
                             "line longer than " + std::to_string(kMax) + " bytes (the limit)");
      }
      if (!text->empty() && text->back() == '\r') text->pop_back();
      if (line_ == 1 && text->compare(0, 3, "\xEF\xBB\xBF") == 0) text->erase(0, 3);
      if (text->find('\0') != std::string::npos) {
        throw io::InputError(
            name_, line_, "", "",
            "NUL byte in the line (a binary or UTF-16 file? expected ASCII/UTF-8 text)");
      }
      if (text->find('\r') != std::string::npos) {
        throw io::InputError(name_, line_, "", "",
                             "carriage return inside a line: the file has CR-only line ends "
                             "(convert them to LF or CRLF)");
      }
      const std::string t = trim(*text);
      if (t.empty() || t[0] == '#') continue;
      return true;
    }
    if (in_->bad()) {
      throw io::InputError(name_, line_ + 1, "", "",
                           std::string("read error: ") + std::strerror(errno));
    }
    return false;
  }

  void read_header() {
    std::string text;
    if (!next_line(&text)) {
      throw io::InputError(name_, 0, "", "",
                           "empty file (expected a header line naming t,v,r,delta)");
    }
    split(text, &header_);
    if (header_.size() > io::kCsvMaxColumns) {
      throw io::InputError(name_, line_, "", "",
                           "the header has " + std::to_string(header_.size()) +
                               " columns (at most " + std::to_string(io::kCsvMaxColumns) + ")");
    }
    for (std::string& h : header_) h = trim(h);
    std::set<std::string> names;
    for (std::size_t i = 0; i < header_.size(); ++i) {
      if (!header_[i].empty() && !names.insert(header_[i]).second) {
        throw io::InputError(name_, line_, header_[i], text, "column named twice in the header");
      }
      for (int k = 0; k < 4; ++k) {
        if (header_[i] == kRequired[k]) col_[k] = static_cast<int>(i);
      }
      if (header_[i] == "u") col_u_ = static_cast<int>(i);
    }
    for (int k = 0; k < 4; ++k) {
      if (col_[k] < 0) {
        throw io::InputError(name_, line_, kRequired[k], text,
                             "required column missing from the header (need t,v,r,delta)");
      }
    }
  }

  std::unique_ptr<std::istream> in_;
  std::string name_;
  std::size_t line_ = 0;
  std::size_t rows_ = 0;
  std::vector<std::string> header_;
  int col_[4] = {-1, -1, -1, -1};
  int col_u_ = -1;
  std::vector<std::string> fields_;
  std::vector<char> buffer_;
};

}  // namespace usvfdi::reference
