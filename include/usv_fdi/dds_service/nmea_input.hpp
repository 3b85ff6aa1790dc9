// The sidecar's live NMEA input (service.input: nmea): a thread that polls the UDP socket
// (nmea_udp::NmeaUdpReceiver, 100 ms poll timeout, so stop() is prompt) and hands every
// assembled sample to the pipeline where the DDS listeners hand theirs (push_rudder, then
// push_ins, at the sample's grid time). A missing value is not invented:
//   delta missing (RSA stale or status V)  -> no rudder sample: after rudder_timeout the
//                                             pipeline reports the rudder missing
//                                             (INPUT_RUDDER_MISSING), as for a silent DDS
//                                             rudder topic;
//   v or r missing (VBW / ROT)              -> that channel flagged invalid (v_valid, r_valid
//                                             false): the engine's stale check reports it;
//   v and r missing                         -> no INS sample: INS silent after input_timeout.
// Which sentence stopped is said in FdiStatus.message (status_note()), and logged when it
// stops and when it is back. Refused lines and datagrams are counted by reason and logged at
// most once per log period (the first few in full, then a summary).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>

#include "usv_fdi/nmea_udp/udp.hpp"
#include "usv_fdi/pipeline/pipeline.hpp"

namespace usvfdi::dds_service {

class NmeaInput {
 public:
  using LogSink = std::function<void(int level, const std::string&)>;
  /// Opens the socket (throws std::runtime_error naming the address and the reason).
  NmeaInput(const nmea_udp::ReceiverConfig& config, pipeline::FdiPipeline* pipeline, LogSink log,
            double log_period = 10.0);
  ~NmeaInput();
  NmeaInput(const NmeaInput&) = delete;
  NmeaInput& operator=(const NmeaInput&) = delete;

  void start();
  /// Ends the thread (within one poll timeout). Idempotent.
  void stop();

  /// For FdiStatus.message: "NMEA RSA stale 2.1 s (delta); 4 lines lost; " ("" : all well).
  std::string status_note() const;
  nmea_udp::DecoderStats stats() const;
  const std::string& describe() const { return rx_->describe(); }
  int receive_buffer() const { return rx_->receive_buffer(); }
  std::uint16_t port() const { return rx_->port(); }

 private:
  void loop();
  void hand_over();
  void review(std::chrono::steady_clock::time_point now);
  void log(int level, const std::string& msg) const {
    if (log_) log_(level, msg);
  }

  nmea_udp::ReceiverConfig config_;
  std::unique_ptr<nmea_udp::NmeaUdpReceiver> rx_;
  pipeline::FdiPipeline* pipeline_;
  LogSink log_;
  std::chrono::steady_clock::duration log_period_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  bool started_ = false;

  // Receive thread only.
  std::chrono::steady_clock::time_point last_datagram_{}, last_log_{};
  bool any_datagram_ = false;
  bool silent_logged_ = false;
  bool origin_logged_ = false;
  std::set<std::string> stale_logged_;  ///< sentences whose stop was logged
  std::uint64_t bad_logged_ = 0;
  std::uint64_t lost_logged_ = 0;
  int socket_errors_ = 0;

  mutable std::mutex m_;  ///< guards note_ and stats_ (read by the publisher thread)
  std::string note_;
  nmea_udp::DecoderStats stats_;
};

}  // namespace usvfdi::dds_service
