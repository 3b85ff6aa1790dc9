// CSV input (header + rows of t, v, r, delta) and the simulator's CSV output.
//
// Input: the header names the columns; t, v, r and delta are required in any order, u (the
// surge speed through the water [m/s], core/speed.hpp) is read when present, other columns
// are ignored. A field `nan`, `NaN` or empty is a missing value (NaN). Numbers are
// read as strtod (C locale) reads them, and trailing garbage is an error: in place by
// std::from_chars when they are plain decimals, by strtod otherwise (a leading '+', hex
// floats, inf, values out of range). The input is read in blocks and parsed where it lies, so
// that a row costs no allocation. Blank lines and lines
// starting with '#' are skipped; CRLF line ends and a UTF-8 byte order mark are accepted.
// Refused with an InputError: a NUL byte (a binary or UTF-16 file), a carriage return inside
// a line (CR-only line ends), a line longer than kCsvMaxLine bytes (read no further than
// one block past that) and a header of more than kCsvMaxColumns columns.
//
// Output: simulator rows with %.17g, so that sim -> CSV -> replay reproduces every double
// bit for bit (a replay of the CSV gives exactly the events of the in-memory run).
#pragma once

#include <cstddef>
#include <iosfwd>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/types.hpp"

namespace usvfdi::io {

/// Longest line accepted [bytes] (a data row of 11 doubles at %.17g is under 300).
constexpr std::size_t kCsvMaxLine = 65536;
/// Most columns accepted in the header.
constexpr std::size_t kCsvMaxColumns = 1024;

/// A problem with an input file: "<file>:<line>: column '<name>': <reason>: '<text>'".
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, std::size_t line, const std::string& column,
             const std::string& text, const std::string& reason);
  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }  ///< 1-based; 0 when no line applies
  const std::string& column() const { return column_; }
  const std::string& text() const { return text_; }

 private:
  std::string file_;
  std::size_t line_;
  std::string column_;
  std::string text_;
};

/// Parses one CSV field as a double: empty / nan / NaN -> NaN; false on anything else
/// strtod cannot consume completely (surrounding blanks are allowed).
bool parse_csv_number(const std::string& field, double* out);

/// Streaming reader of Samples from a CSV file.
class CsvSampleReader {
 public:
  /// Opens the file and reads its header. Throws InputError.
  explicit CsvSampleReader(const std::string& path);
  /// Reads from a stream; `name` stands for the file name in messages. Throws InputError.
  CsvSampleReader(std::unique_ptr<std::istream> in, const std::string& name);
  ~CsvSampleReader();
  CsvSampleReader(const CsvSampleReader&) = delete;
  CsvSampleReader& operator=(const CsvSampleReader&) = delete;

  /// Reads the next row into *s. Returns false at the end of the file. Throws InputError on
  /// a malformed row (the reader should not be used after that).
  bool next(Sample* s);

  const std::string& name() const { return name_; }
  /// Line number of the last line read (1-based).
  std::size_t line() const { return line_; }
  /// Rows returned so far.
  std::size_t rows() const { return rows_; }
  const std::vector<std::string>& header() const { return header_; }

 private:
  void read_header();
  /// The next line that is neither blank nor a comment, as a view into buffer_ (valid until
  /// the next call), without its line end and, on line 1, its byte order mark.
  bool next_line(std::string_view* text);
  /// Moves the unread bytes to the front of buffer_ and reads a block after them; false when
  /// nothing more could be read.
  bool fill();

  std::unique_ptr<std::istream> in_;
  std::string name_;
  std::size_t line_ = 0;
  std::size_t rows_ = 0;
  std::vector<std::string> header_;
  int col_[4] = {-1, -1, -1, -1};         ///< field index of t, v, r, delta
  int col_u_ = -1;                        ///< field index of the optional u
  std::vector<std::string_view> fields_;  ///< the current line's fields, views into buffer_
  std::vector<char> buffer_;  ///< the longest line (kCsvMaxLine + 2 bytes) and a block more
  std::size_t begin_ = 0;     ///< buffer_[begin_, end_): read from the input, not yet parsed
  std::size_t end_ = 0;
  bool eof_ = false;  ///< the input has no more bytes
};

/// Writes simulator rows: t,v,r,delta,v_true,r_true,delta_true,psi,psi_ref,fault_a,fault_g
/// (numbers %.17g; fault columns hold the kind name, empty when healthy).
class SimCsvWriter {
 public:
  /// Writes the header.
  explicit SimCsvWriter(std::ostream& out);
  void write(const SimRow& row);

 private:
  std::ostream& out_;
};

}  // namespace usvfdi::io
