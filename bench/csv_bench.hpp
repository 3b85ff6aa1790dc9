// Replay input cost (csv_bench.cpp): registered by usv_fdi_bench's main.
#pragma once

namespace usvfdi::bench {

/// Registers the CSV benchmarks (minimal parse, reader, reader before, whole replay).
void register_csv();

/// Issue 14's target for the whole replay: at most this many times the minimal parse.
constexpr double kReplayTargetRatio = 1.5;

}  // namespace usvfdi::bench
