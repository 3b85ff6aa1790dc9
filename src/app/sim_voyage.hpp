// usv-fdi sim with a voyage scenario: any hull (shipped vessels and the vessel zoo) under
// the voyage simulator of src/sim (autopilot, manoeuvres, waves, wind, current, sensors).
#pragma once

#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "usv_fdi/sim/hull.hpp"
#include "usv_fdi/sim/voyage.hpp"

namespace usvfdi::app {

/// The options of `usv-fdi sim` that only voyages take.
struct VoyageArgs {
  std::optional<int> sea_state;
  std::optional<double> wave_period;
  std::string current;  ///< SPEED[:SET_DEG]
  std::string wind;     ///< DEG[:GUST_DEG]
  std::vector<std::string> sensor;
  std::string fault_set;
  std::vector<std::string> sigma_faults;
  std::string dither;  ///< DEG[:PERIOD]
  std::string side;    ///< first side of zigzags and turning circles (empty: starboard)
  /// True when any voyage-only option was given (an error with a classic scenario).
  bool any() const;
};

/// The common options of `usv-fdi sim` a voyage uses too.
struct VoyageCommon {
  std::string vessel, scenario, output;
  double rate_hz = 50.0;
  std::optional<double> duration;
  std::uint64_t seed = 1;
  double noise_scale = 1.0;
  std::vector<std::string> faults;  ///< channel units, as in the classic scenarios
  bool nmea = false;                ///< write NMEA sentences instead of CSV rows
  bool nmea_heading = false;        ///< --nmea: also $HEHDT
};

/// Calls write_next() (write the next row; false when there is none) until it returns false,
/// counting the rows in *rows. False (logged) when it throws std::runtime_error: a value that
/// no NMEA sentence can hold.
template <class WriteNext>
bool write_rows(WriteNext write_next, std::size_t* rows) {
  try {
    while (write_next()) ++*rows;
  } catch (const std::runtime_error& e) {
    spdlog::error("{}", e.what());
    return false;
  }
  return true;
}

/// Every hull `--vessel` accepts with a voyage scenario.
std::vector<std::string> voyage_vessel_names();
/// The hull of that name (the zoo's, else a shipped vessel as a linear hull); nullptr if none.
std::shared_ptr<const sim::Hull> find_voyage_hull(const std::string& name);
void add_voyage_options(CLI::App* sub, VoyageArgs* a);
/// The voyage the options describe, with this seed (and its configuration in *cfg if not
/// null); nullptr (logged) on a bad option.
std::unique_ptr<sim::Voyage> make_voyage(const VoyageCommon& common, const VoyageArgs& a,
                                         std::uint64_t seed, sim::VoyageConfig* cfg = nullptr);
/// Runs the voyage and writes its CSV (or NMEA log); returns the exit code.
int run_voyage_sim(const VoyageCommon& common, const VoyageArgs& a);

}  // namespace usvfdi::app
