// NMEA 0183 / IEC 61162-450 logs: the replay's input (samples assembled from ROT, RSA, VBW and
// VTG lines) and the simulator's NMEA output.
//
// Input, one line at a time (blank lines and lines starting with '#' are skipped; LF or CR LF):
//   $HEROT,12.34,A*hh                     a plain NMEA 0183 sentence
//   \s:HE0001,c:1767225600100*hh\$HEROT,...  a sentence after a TAG block
//   UdPbC<NUL>\s:...*hh\$HEROT,...        an IEC 61162-450 datagram's first line (the NUL may be
//                                         missing in a text log); the datagram's further
//                                         sentences follow on their own lines
// Time of a line: the c: of its TAG block (UNIX time, read as seconds, or milliseconds from 11
// digits on; nmea/datagram.hpp) less the log's first c:, so that t = 0 at the first TAG time
// (the output's 9 significant digits keep the tenths); else the latest c: seen before it (the
// other sentences of a datagram share its TAG block). Before any c:, and only when a sentence rate
// is given (NmeaInputOptions::cycle_rate_hz, `--nmea-rate`), the time is k / rate where k counts
// cycles: a cycle ends when a sentence address (talker and formatter) repeats. Otherwise the
// line has no time and is counted as unusable.
// The assembled samples (nmea/assembler.hpp) lie on the grid k / grid_rate_hz; the sign of the
// rudder angle is the vessel model's (nmea::rudder_sign_from_b2 of the configured B).
//
// Unusable lines never stop the replay: each is counted under its reason (checksum mismatch,
// malformed, out of range, status V, no time, time going back, ...) with its first line. Lines
// of other sentence formatters (HDT, THS, GGA, proprietary, ...) are ignored, not unusable; any
// talker is accepted.
//
// Output (sim --nmea): per simulator row a TAG block with c: (epoch + t, in milliseconds) and
// n: (line count), then $HEROT (r), $AGRSA (delta, sign by B), $VDVBW (v; u), optionally
// $HEHDT (psi). Talkers: HE heading, north-seeking gyro (ROT, HDT); AG autopilot, general
// (RSA); VD velocity sensor, Doppler, other/general (VBW): the nmea library's defaults, as the
// talker tables of open-source NMEA parsers found with the search tool name them (they also
// list TI turn rate indicator and RI rudder angle indicator; a replay accepts any talker).
// Rounding: ROT 3 decimals [deg/min], RSA 3 decimals [deg], VBW 4 decimals [kn], HDT 2 decimals
// [deg] (kNmeaDecimals*), far below the vessels' sensor noise, so that the engine's stuck check
// does not take the quantisation for a stuck sensor.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/types.hpp"

namespace usvfdi::nmea {
class SampleAssembler;
}

namespace usvfdi::io {

/// Decimals written by NmeaSimWriter.
constexpr int kNmeaDecimalsRot = 3;      ///< deg/min: 1e-3 deg/min = 2.9e-7 rad/s
constexpr int kNmeaDecimalsRudder = 3;   ///< deg: 1e-3 deg = 1.7e-5 rad
constexpr int kNmeaDecimalsSpeed = 4;    ///< kn: 1e-4 kn = 5.1e-5 m/s
constexpr int kNmeaDecimalsHeading = 2;  ///< deg
/// Longest line used [bytes]; a longer one is counted as too long.
constexpr std::size_t kNmeaMaxLine = 4096;

struct NmeaInputOptions {
  double b2 = -1.0;            ///< the configured B(1): the sign of delta (rudder_sign_from_b2)
  double grid_rate_hz = 10.0;  ///< rate of the assembled samples [Hz]
  /// Sentence cycle rate of a log without TAG times [Hz]; empty: such lines have no time.
  std::optional<double> cycle_rate_hz;
  double max_age_s = 1.0;  ///< a value older than this is missing in a sample [s]
  /// Nearest grid time, not again once the sentence's next is overdue
  /// (nmea::AssemblerConfig::hold_until_due).
  bool hold_until_due = false;
};

/// Lines counted under one reason.
struct NmeaLineCount {
  std::uint64_t count = 0;
  std::size_t first_line = 0;  ///< 1-based
  std::string first_text;      ///< what was wrong with the first one
};

/// What the reader made of the lines read so far.
struct NmeaLineStats {
  std::uint64_t lines = 0;     ///< non-blank, non-comment lines
  std::uint64_t used = 0;      ///< ROT, RSA, VBW, VTG lines read into the samples
  std::uint64_t ignored = 0;   ///< other sentence formatters (HDT, THS, GGA, proprietary ...)
  std::uint64_t unusable = 0;  ///< the sum of `reasons`
  std::map<std::string, NmeaLineCount> reasons;  ///< "checksum mismatch", "status V", ...
  /// "12 checksum mismatch (first: line 7), 3 status V (first: line 40)".
  std::string describe() const;
};

/// Streaming reader of Samples from an NMEA log (the replay's input).
class NmeaSampleReader {
 public:
  /// Opens the file. Throws InputError (file cannot be opened) or std::invalid_argument (a
  /// rate or age that is not finite and > 0).
  NmeaSampleReader(const std::string& path, const NmeaInputOptions& options);
  /// Reads from a stream; `name` stands for the file name in messages.
  NmeaSampleReader(std::unique_ptr<std::istream> in, const std::string& name,
                   const NmeaInputOptions& options);
  ~NmeaSampleReader();
  NmeaSampleReader(const NmeaSampleReader&) = delete;
  NmeaSampleReader& operator=(const NmeaSampleReader&) = delete;

  /// The next assembled sample; false at the end of the file. Never throws on bad lines.
  bool next(Sample* s);

  const std::string& name() const { return name_; }
  /// The line read when the last sample was completed (1-based).
  std::size_t line() const { return line_; }
  /// Samples returned so far.
  std::size_t rows() const { return rows_; }
  /// The log's first TAG time c: [ms since 1970-01-01 UTC], t = 0 of the samples; empty
  /// when no line had one.
  std::optional<std::int64_t> first_tag_ms() const { return first_tag_ms_; }
  const NmeaLineStats& stats() const { return stats_; }

 private:
  void read_line(const std::string& text);
  void count(const std::string& reason, const std::string& text);
  std::optional<double> line_time(const std::string& address, const std::optional<double>& tag_t);
  bool refill();

  std::unique_ptr<std::istream> in_;
  std::string name_;
  NmeaInputOptions options_;
  std::unique_ptr<nmea::SampleAssembler> assembler_;
  std::vector<Sample> pending_;
  std::size_t next_pending_ = 0;
  std::size_t line_ = 0;
  std::size_t rows_ = 0;
  bool eof_ = false;
  std::optional<std::int64_t> first_tag_ms_;  ///< the log's first c: [ms since 1970]
  std::optional<double> last_tag_t_;          ///< the latest c: [s since the first]
  double latest_t_ = kNaN;                    ///< the latest time given to the assembler [s]
  std::uint64_t cycle_ = 0;                   ///< --nmea-rate: cycles so far
  std::vector<std::string> cycle_addresses_;
  NmeaLineStats stats_;
};

/// UNIX time of the simulator's t = 0 in its NMEA output: 2026-01-01T00:00:00Z [ms].
constexpr std::int64_t kNmeaSimEpochMs = 1767225600000;

struct NmeaOutputOptions {
  double b2 = -1.0;          ///< the vessel's B(1): the sign of the RSA written
  double surge_speed = 0.0;  ///< VBW longitudinal water speed when a row has no u [m/s]
  std::int64_t epoch_ms = kNmeaSimEpochMs;  ///< UNIX time of t = 0 [ms] (c: = epoch + t)
  bool heading = false;                     ///< also $HEHDT from psi
  std::string source = "HE0001";            ///< TAG s: (the sender)
};

/// Writes simulator rows as NMEA 0183 sentences with TAG blocks (see above).
class NmeaSimWriter {
 public:
  NmeaSimWriter(std::ostream& out, const NmeaOutputOptions& options);
  /// One row; `u` its surge speed [m/s] (NaN: options.surge_speed). Throws std::runtime_error
  /// on a value no sentence can hold (a rudder beyond 90 deg, a time before 1970-04-26).
  void write(double t, double v, double r, double delta, double psi, double u = kNaN);
  void write(const SimRow& row) { write(row.t, row.v, row.r, row.delta, row.psi); }

 private:
  void put(const std::string& sentence, double t);
  std::ostream& out_;
  NmeaOutputOptions options_;
  std::int64_t line_count_ = 0;
};

}  // namespace usvfdi::io
