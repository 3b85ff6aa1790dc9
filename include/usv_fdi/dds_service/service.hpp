// The usv-fdi sidecar: the FDI pipeline behind Fast DDS readers and writers.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "usv_fdi/core/engine.hpp"
#include "usv_fdi/dds/dds_context.hpp"
#include "usv_fdi/dds_service/journal.hpp"
#include "usv_fdi/dds_service/nmea_input.hpp"
#include "usv_fdi/dds_service/status_uplink.hpp"
#include "usv_fdi/nmea_udp/udp.hpp"
#include "usv_fdi/pipeline/pipeline.hpp"

namespace usvfdi::dds_service {

/// Where the sidecar's INS and rudder samples come from (service.input).
enum class InputSource {
  kDds,   ///< InsSample / RudderSample topics (the default)
  kNmea,  ///< NMEA 0183 / IEC 61162-450 over UDP (service.nmea; nmea_udp/udp.hpp)
};

struct ServiceConfig {
  EngineConfig engine;
  pipeline::PipelineOptions pipeline;
  usvfdi::dds::DdsConfig dds;
  std::uint32_t mmsi = 0;        ///< the vessel this sidecar watches (required, > 0)
  bool reliable_inputs = false;  ///< INS and rudder readers RELIABLE instead of BEST_EFFORT
  /// INS, rudder and ack readers on content-filtered topics "mmsi = <mmsi>": writers that filter
  /// on their side send them nothing of other vessels (false: every sample of the partition
  /// arrives and other vessels' are dropped after their receipt). Off by default: under
  /// ThreadSanitizer a Fast DDS 2.9 writer crashed in its SQL filter evaluation while a
  /// filtered reader went away (docs/dds.md).
  bool content_filter = false;
  std::string log_level = "info";
  std::string config_file;  ///< where it was loaded from (for messages)
  /// Directory of the state journal (latched faults survive a restart); "" : none.
  std::string state_dir;
  /// false: state_dir is the default (kDefaultStateDir), used only if it exists;
  /// true: set by service.state_dir or --state-dir (created if missing; "" disables).
  bool state_dir_explicit = false;
  std::string health_file;  ///< service.health_file / --health-file ("" : none)
  /// service.metrics / --metrics: "host:port" of the Prometheus endpoint ("" : none; port 0:
  /// any free port, logged).
  std::string metrics;
  InputSource input = InputSource::kDds;
  /// service.nmea (input: nmea): the socket and the sample assembler; the rudder sign is
  /// model.B's (nmea::rudder_sign_from_b2).
  nmea_udp::ReceiverConfig nmea;
  /// service.status_uplink: which statuses are sent (event-triggered by default).
  UplinkOptions uplink;
};

/// Whether `s` is HOST:PORT as service.metrics takes it: a host name or address (IPv6 in
/// brackets) and a port 0-65535, nothing else.
bool is_host_port(const std::string& s);

/// Loads the engine keys (see usv_fdi/io/config.hpp) and the `service:` section:
///   mmsi, domain_id, qos_profiles (path, relative to the config file), participant_profile,
///   topics: {ins, rudder, fault_event, fault_ack, status, speed}, partitions: [..],
///   reliable_inputs, content_filter, estimate_wait [s], status_rate [Hz], log_level,
///   authorised_operators: [..], input_queue, rudder_wait, rudder_timeout, speed_max_age,
///   input_timeout, restore_recheck, status_uplink: {mode, heartbeat, tolerance, theta, decay},
///   state_dir (relative to the config file; "" : no persistence), health_file,
///   metrics,
///   input (dds | nmea), nmea: {address, port, interface, rate, max_age, receive_buffer}.
/// state_dir defaults to kDefaultStateDir (used if it exists).
/// Throws usvfdi::io::ConfigError naming file, key, line and value.
ServiceConfig load_service_config(const std::string& path);

/// The QoS profiles file used when no config names one: $USV_FDI_QOS_PROFILES, else the
/// file shipped in the source tree's config/qos/.
std::string default_qos_profiles();

/// Thrown by FdiService when another process holds the state directory's lock for this
/// vessel (a second sidecar for the same MMSI on the same state directory).
class StateInUse : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class FdiService {
 public:
  using LogSink = pipeline::FdiPipeline::LogSink;
  /// Creates every DDS entity and the pipeline; throws std::runtime_error naming what failed,
  /// StateInUse when another sidecar holds <state_dir>/usv-fdi-<mmsi>.lock.
  FdiService(const ServiceConfig& cfg, LogSink log);
  ~FdiService();
  FdiService(const FdiService&) = delete;
  FdiService& operator=(const FdiService&) = delete;

  void start();
  /// Stops the listeners' feed, drains and joins the threads, deletes the DDS entities.
  /// Idempotent; the destructor calls it.
  void stop();
  pipeline::PipelineStatus status() const { return pipeline_->status(); }
  /// This run's incarnation (FaultEvent.incarnation of the events it issues).
  std::uint64_t incarnation() const { return pipeline_->incarnation(); }
  pipeline::PipelineLiveness liveness() const { return pipeline_->liveness(); }

  /// The state journal's file ("" when state is not persisted) and the error of its last
  /// failed save ("" when fine).
  std::string state_file() const { return journal_ ? journal_->path() : std::string(); }
  std::string state_error() const { return journal_ ? journal_->last_error() : std::string(); }
  /// The fault instances restored from the journal at construction.
  const std::vector<FaultEvent>& restored() const { return restored_; }

  /// Matched remote endpoints (for the operator's log); all zero after stop().
  struct Matches {
    int ins_writers = 0, rudder_writers = 0, ack_writers = 0, speed_writers = 0;
    int event_readers = 0, status_readers = 0;
    bool operator==(const Matches& o) const {
      return ins_writers == o.ins_writers && rudder_writers == o.rudder_writers &&
             ack_writers == o.ack_writers && event_readers == o.event_readers &&
             status_readers == o.status_readers && speed_writers == o.speed_writers;
    }
    bool operator!=(const Matches& o) const { return !(*this == o); }
  };
  Matches matches() const;
  /// Samples on the input topics that carried another vessel's MMSI (skipped).
  std::uint64_t foreign_samples() const;
  /// Distinct other DDS writers seen publishing this vessel's FaultEvents (a second sidecar
  /// with the same MMSI, or a forger), and the samples they wrote.
  std::uint64_t other_event_writers() const;
  std::uint64_t other_event_samples() const;
  /// The live NMEA input (input: nmea), else nullptr.
  const NmeaInput* nmea_input() const { return nmea_.get(); }

 private:
  class Listener;
  class EventWatch;
  void open_journal();
  bool lock_state(const std::string& dir);
  ServiceConfig cfg_;
  LogSink log_;
  std::unique_ptr<StateJournal> journal_;
  std::vector<FaultEvent> restored_;
  std::string journal_error_logged_;  ///< publisher thread: the save error already logged
  std::unique_ptr<pipeline::FdiPipeline> pipeline_;
  std::unique_ptr<Listener> listener_;
  std::unique_ptr<NmeaInput> nmea_;  ///< input: nmea (the INS and rudder readers are not made)
  std::unique_ptr<EventWatch> watch_;
  StatusUplink uplink_;  ///< the publisher thread's, then stop()'s
  /// J_N peaks of statuses the uplink did not send, handed on to the next one sent.
  std::array<double, 2> held_peak_{std::numeric_limits<double>::quiet_NaN(),
                                   std::numeric_limits<double>::quiet_NaN()};
  int lock_fd_ = -1;  ///< <state_dir>/usv-fdi-<mmsi>.lock, flock()ed while the sidecar runs
  std::unique_ptr<usvfdi::dds::DdsContext> dds_;
  /// The participant of the ack reader alone (its own port and receive thread).
  std::unique_ptr<usvfdi::dds::DdsContext> ack_dds_;
  eprosima::fastdds::dds::DataWriter* event_writer_ = nullptr;
  eprosima::fastdds::dds::DataWriter* status_writer_ = nullptr;
  eprosima::fastdds::dds::DataReader* event_watch_ = nullptr;  ///< FaultEvent, for EventWatch
  bool stopped_ = false;
};

}  // namespace usvfdi::dds_service
