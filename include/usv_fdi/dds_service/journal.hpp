// The sidecar's journal of its latched fault state: restart without loss (issue 4).
//
// What must survive a restart (SIGTERM or SIGKILL) is the latch of every fault instance of
// the vessel — at most three (accelerometer, gyro, unknown) — with its sequence number, not
// the history of events. The journal keeps the latest FaultEvent of each instance in one
// small JSON file, <state_dir>/usv-fdi-<mmsi>.state.json, replaced atomically on every
// event (write <file>.tmp, fsync, rename over the file, fsync the directory): after a crash
// the file holds either the previous or the new state, never a mix. It is written by the
// publisher thread BEFORE the event is handed to DDS, so no sequence number a subscriber has
// seen is missing from the file. On start the sidecar restores every instance into its
// latches (FdiPipeline::restore) and re-publishes it with the same sequence.
//
// File format (version 1; the checksum covers every byte before its line):
//   {
//     "format": "usv-fdi fault state",
//     "version": 1,
//     "mmsi": 257000001,
//     "written": 1732370000.123,
//     "instances": [
//       {"sensor":"gyro","state":"raised","kind":"bias","sequence":3,
//        "incarnation":1764624000123456,"c_a":0.01,"c_g":0.99,"statistic":14.1,"threshold":6,
//        "onset_time":20,"detection_time":20.4,"stamp":20.4,"a":[-0.1,0.2,0.3,-0.4],
//        "message":"..."}   (one line each: io::fault_event_fields, as the replay and the
//                            monitor write a fault event; files of earlier versions, with
//                            the same fields spread over three lines, are read alike)
//     ],
//     "checksum": "fnv1a64:0123456789abcdef"
//   }
// Numbers are written with 17 significant digits (exact round trip); NaN as null.
// "incarnation" (the sidecar run that issued the sequence) may be missing (files written
// before it existed): 0. A file that is not a regular file (a FIFO, a directory) is refused
// without blocking.
#pragma once

#include <array>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "usv_fdi/core/latch.hpp"

namespace usvfdi::dds_service {

/// Where the sidecar keeps its state when neither service.state_dir nor --state-dir is given:
/// used if the directory exists (the container images and packages create it), otherwise
/// nothing is persisted and the sidecar says so at start.
inline constexpr const char* kDefaultStateDir = "/var/lib/usv-fdi";

class StateJournal {
 public:
  static constexpr int kVersion = 1;

  /// The state file of a vessel in a state directory.
  static std::string path_for(const std::string& dir, std::uint32_t mmsi);

  struct Contents {
    std::vector<FaultEvent> events;  ///< one per instance, in sensor order
    double written = 0.0;            ///< when the file was written [s since the Unix epoch]
  };

  /// The file's text for these events (the latest of each instance).
  static std::string serialise(std::uint32_t mmsi, const std::vector<FaultEvent>& events,
                               double written);
  /// Parses and checks a file's text: format, version, MMSI, checksum, every field. Returns
  /// false with *error saying what is wrong (without the file name).
  static bool parse(const std::string& text, std::uint32_t mmsi, Contents* out, std::string* error);

  enum class LoadResult : std::uint8_t { kLoaded, kMissing, kError };
  /// Reads the file at `path`. kMissing: no such file (a first start). kError: *error names
  /// the file and what was wrong (unreadable, not a regular file, not JSON, wrong version or
  /// MMSI, checksum ...). Never blocks: a FIFO or device at `path` is refused without reading.
  static LoadResult load(const std::string& path, std::uint32_t mmsi, Contents* out,
                         std::string* error);

  /// Replaces `path` by `text` atomically and durably: <path>.tmp, fsync, rename, fsync of
  /// the directory. Returns false with *error (path and errno text); `path` is then unchanged.
  static bool write_atomic(const std::string& path, const std::string& text, std::string* error);

  /// "a FIFO (named pipe)", "a directory", ... for a stat mode.
  static std::string file_type(unsigned mode);

  /// Renames a bad state file to <path>.corrupt-<UTC time> so that it is kept for inspection
  /// and not read again. Returns the new name, or "" (with *error) if that failed.
  static std::string set_aside(const std::string& path, std::string* error);

  StateJournal(std::string path, std::uint32_t mmsi) : path_(std::move(path)), mmsi_(mmsi) {}
  const std::string& path() const { return path_; }

  /// Takes a restored event as the instance's current state (no write).
  void seed(const FaultEvent& ev);
  /// Records an event as its instance's latest state and saves the file. Returns false (and
  /// keeps the error for last_error()) if the file could not be written.
  bool record(const FaultEvent& ev);
  /// Saves the current state (the seeded or recorded events); see record().
  bool save();
  /// The error of the last failed save, "" once a save succeeded again. Thread-safe.
  std::string last_error() const;
  std::uint64_t saves() const;

 private:
  std::string path_;
  std::uint32_t mmsi_;
  std::array<FaultEvent, 3> latest_{};
  std::array<bool, 3> have_{false, false, false};
  mutable std::mutex m_;  ///< guards error_ and saves_ (read by the health reporter)
  std::string error_;
  std::uint64_t saves_ = 0;
};

}  // namespace usvfdi::dds_service
