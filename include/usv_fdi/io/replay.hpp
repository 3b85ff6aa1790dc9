// Offline replay: CSV samples (or samples assembled from an NMEA log) through FdiEngine into JSON
// Lines records.
#pragma once

#include "usv_fdi/core/engine.hpp"
#include "usv_fdi/io/csv.hpp"
#include "usv_fdi/io/jsonl.hpp"
#include "usv_fdi/io/nmea_log.hpp"

namespace usvfdi::io {

struct ReplayOptions {
  /// An estimate record at least this often [s of data time], and whenever the convergence
  /// or arming flag changes, and one at the end.
  double estimate_period = 1.0;
  /// Acknowledge every raised / cleared event at once (as an attentive operator would), so
  /// that each latch returns to normal when its condition clears.
  bool auto_ack = false;
  /// A signal record (J_N, thresholds, C_a, C_g: what `usv-fdi plot` draws) at the first
  /// sample at or after each multiple of this [s of data time]; 0: none.
  double signal_period = 0.0;
};

/// Feeds every row of `input` to a fresh FdiEngine, writing an event record for every
/// latched-state change, estimate records and a final summary (also returned).
/// On a malformed row, whatever was produced is written, then a final estimate and a
/// summary with complete = false, and the InputError is rethrown.
RunSummary replay(const EngineConfig& cfg, CsvSampleReader& input, JsonlWriter& out,
                  const ReplayOptions& options = {});

/// The same from an NMEA log: one sample per grid time of the reader (its bad lines are
/// counted in input.stats(), never thrown).
RunSummary replay(const EngineConfig& cfg, NmeaSampleReader& input, JsonlWriter& out,
                  const ReplayOptions& options = {});

}  // namespace usvfdi::io
