#include "usv_fdi/dds_service/service.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

#include "usv_fdi/core/text.hpp"
#include "usv_fdi/dds_service/convert.hpp"

namespace usvfdi::dds_service {

using eprosima::fastdds::dds::DataReader;
using eprosima::fastdds::dds::DataReaderListener;
using eprosima::fastdds::dds::StatusMask;
using eprosima::fastrtps::types::ReturnCode_t;

/// Reader listener: copies this vessel's samples into the pipeline's input queue, nothing else
/// (no I/O, no lock of ours; the queue never blocks). Samples of other vessels (same topic,
/// other MMSI) are counted and skipped. Fast DDS may call it from several of its threads at
/// once (one per transport), so it keeps no state but atomics.
class FdiService::Listener : public DataReaderListener {
 public:
  /// `peers`: the participant's directory when it runs DDS Security (nullptr: it does not).
  Listener(pipeline::FdiPipeline* p, std::uint32_t mmsi, const dds::PeerDirectory* peers)
      : p_(p), mmsi_(mmsi), peers_(peers) {}
  void on_data_available(DataReader* reader) override {
    using Info = eprosima::fastdds::dds::SampleInfo;
    if (reader == ins_) {
      drain<fdi::InsSample>(*reader, [this](const fdi::InsSample& s, const Info&) {
        return p_->push_ins(from_dds(s));
      });
    } else if (reader == rudder_) {
      drain<fdi::RudderSample>(*reader, [this](const fdi::RudderSample& s, const Info&) {
        return p_->push_rudder(from_dds(s));
      });
    } else if (reader == speed_) {
      drain<fdi::SpeedSample>(*reader, [this](const fdi::SpeedSample& s, const Info&) {
        return p_->push_speed(from_dds(s));
      });
    } else if (reader == ack_) {
      drain<fdi::FaultAck>(*reader, [this](const fdi::FaultAck& a, const Info& info) {
        pipeline::AckInput in = from_dds(a);
        // Under DDS Security the operator is the writer's authenticated identity, not what the
        // sample claims.
        if (peers_ != nullptr) {
          in.who = escape_text(dds::operator_of(peers_->subject_of(info.publication_handle),
                                                a.operator_id().to_string()));
        }
        return p_->push_ack(in);
      });
    }
  }
  DataReader* ins_ = nullptr;
  DataReader* rudder_ = nullptr;
  DataReader* speed_ = nullptr;
  DataReader* ack_ = nullptr;
  std::atomic<std::uint64_t> foreign{0};  ///< samples of other vessels, skipped

 private:
  template <class T, class Push>
  void drain(DataReader& reader, Push push) {
    T sample;
    eprosima::fastdds::dds::SampleInfo info;
    while (reader.take_next_sample(&sample, &info) ==
           eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      if (sample.mmsi() != mmsi_) {
        foreign.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      push(sample, info);  // a full queue drops its oldest element and counts it
    }
  }

  pipeline::FdiPipeline* p_;
  std::uint32_t mmsi_;
  const dds::PeerDirectory* peers_;
};

/// Watches the FaultEvent topic for this vessel's instances written by anyone but this
/// sidecar: a second sidecar with the same MMSI (every event would reach the monitors twice)
/// or a forger. Says so loudly: an error line per new writer, then a count every 10 s while
/// it goes on; the status carries a flag and the count.
class FdiService::EventWatch : public DataReaderListener {
 public:
  EventWatch(std::uint32_t mmsi, eprosima::fastdds::dds::InstanceHandle_t own,
             FdiService::LogSink log)
      : mmsi_(mmsi), own_(own), log_(std::move(log)) {}
  void on_data_available(DataReader* reader) override {
    fdi::FaultEvent e;
    eprosima::fastdds::dds::SampleInfo info;
    while (reader->take_next_sample(&e, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data || e.mmsi() != mmsi_ || info.publication_handle == own_) continue;
      std::ostringstream guid;
      guid << info.publication_handle;
      const auto now = std::chrono::steady_clock::now();
      std::string line;
      {
        std::lock_guard<std::mutex> lock(m_);
        ++samples_;
        last_seen_ = now;
        seen_any_ = true;
        if (writers_.insert(guid.str()).second) {
          line = "ANOTHER WRITER publishes FaultEvents of this vessel (MMSI " +
                 std::to_string(mmsi_) + "): writer " + guid.str() + " wrote " +
                 sensor_name(e.sensor()) + " #" + std::to_string(e.sequence()) + " (incarnation " +
                 std::to_string(e.incarnation()) +
                 "): a second sidecar for this MMSI, or a forger; monitors cannot tell its "
                 "events from this sidecar's (" +
                 std::to_string(writers_.size()) + " other writer(s) so far)";
          last_logged_ = now;
          logged_samples_ = samples_;
        } else if (now - last_logged_ >= std::chrono::seconds(10)) {
          line = "ANOTHER WRITER still publishes FaultEvents of MMSI " + std::to_string(mmsi_) +
                 ": " + std::to_string(samples_ - logged_samples_) + " more sample(s) from " +
                 std::to_string(writers_.size()) + " other writer(s)";
          last_logged_ = now;
          logged_samples_ = samples_;
        }
      }
      if (!line.empty() && log_) log_(3, line);
    }
  }
  std::uint64_t writers() const {
    std::lock_guard<std::mutex> lock(m_);
    return writers_.size();
  }
  std::uint64_t samples() const {
    std::lock_guard<std::mutex> lock(m_);
    return samples_;
  }
  /// True while another writer has written within `window`.
  bool recent(std::chrono::steady_clock::duration window) const {
    std::lock_guard<std::mutex> lock(m_);
    return seen_any_ && std::chrono::steady_clock::now() - last_seen_ <= window;
  }

 private:
  static std::string sensor_name(std::uint8_t s) {
    return s <= 2 ? to_string(static_cast<Sensor>(s)) : "sensor " + std::to_string(s);
  }
  std::uint32_t mmsi_;
  eprosima::fastdds::dds::InstanceHandle_t own_;
  FdiService::LogSink log_;
  mutable std::mutex m_;
  std::set<std::string> writers_;
  std::uint64_t samples_ = 0, logged_samples_ = 0;
  bool seen_any_ = false;
  std::chrono::steady_clock::time_point last_seen_{}, last_logged_{};
};

FdiService::FdiService(const ServiceConfig& cfg, LogSink log)
    : cfg_(cfg), log_(std::move(log)), uplink_(cfg.uplink) {
  if (cfg_.mmsi == 0) throw std::invalid_argument("service.mmsi must be set (a vessel's MMSI > 0)");
  dds_ = std::make_unique<dds::DdsContext>(cfg_.dds);
  event_writer_ = &dds_->create_writer(dds::TopicId::kFaultEvent, dds::profiles::kFaultEventWriter);
  status_writer_ = &dds_->create_writer(dds::TopicId::kStatus, dds::profiles::kStatusWriter);
  const std::uint32_t mmsi = cfg_.mmsi;
  const IsolationParams iso = cfg_.engine.isolation;
  open_journal();
  auto on_event = [this, mmsi](const FaultEvent& e) {
    // Persisted before it is published: a sequence a subscriber has seen is in the file.
    if (journal_) {
      if (!journal_->record(e)) {
        const std::string err = journal_->last_error();
        if (err != journal_error_logged_ && log_) {
          log_(3, "state: cannot save the latched fault state: " + err +
                      " (events are still published, but will not survive a restart)");
        }
        journal_error_logged_ = err;
      } else if (!journal_error_logged_.empty()) {
        if (log_) log_(1, "state: saved again to " + journal_->path());
        journal_error_logged_.clear();
      }
    }
    dds::write(*event_writer_, to_dds(e, mmsi));
    if (log_) {
      char head[192];
      std::snprintf(head, sizeof head,
                    "fault event MMSI %u %s #%llu %s kind=%s C_a=%.3f C_g=%.3f t=%.2f s", mmsi,
                    to_string(e.sensor), static_cast<unsigned long long>(e.sequence),
                    to_string(e.state), to_string(e.kind), e.c_a, e.c_g, e.t);
      log_(1, std::string(head) + ": " + e.message);
    }
  };
  auto on_status = [this, mmsi, iso](const pipeline::PipelineStatus& s) {
    fdi::FdiStatus d = to_dds(s, mmsi, iso);
    if (nmea_) {
      // The input's own words first: which sentence stopped, lines lost or refused.
      const std::string note = nmea_->status_note();
      if (!note.empty()) d.message((note + d.message().to_string()).substr(0, 127).c_str());
    }
    if (watch_) {
      if (watch_->recent(std::chrono::seconds(10))) {
        d.input_flags(d.input_flags() | pipeline::kInputOtherEventWriter);
      }
      d.other_event_writers(watch_->writers());
    }
    const double now =
        std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    // A status not sent hands its J_N peaks on to the next one, so the shore sees every peak.
    std::array<double, 2> peak = d.j_peak();
    for (std::size_t c = 0; c < 2; ++c) {
      if (std::isnan(peak[c]) || held_peak_[c] > peak[c]) peak[c] = held_peak_[c];
    }
    d.j_peak(peak);
    if (uplink_.offer(d, now) != UplinkReason::kNone) {
      dds::write(*status_writer_, d);
      held_peak_.fill(std::numeric_limits<double>::quiet_NaN());
    } else {
      held_peak_ = peak;
    }
  };
  // This run's incarnation: its start time (microseconds since the Unix epoch), above that
  // of every restored event even if the clock went back.
  pipeline::PipelineOptions popt = cfg_.pipeline;
  if (popt.incarnation == 0) {
    std::uint64_t floor = 0;
    for (const FaultEvent& e : restored_) floor = std::max(floor, e.incarnation);
    const auto now_us =
        static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                       std::chrono::system_clock::now().time_since_epoch())
                                       .count());
    popt.incarnation = std::max(now_us, floor + 1);
  }
  pipeline_ = std::make_unique<pipeline::FdiPipeline>(cfg_.engine, popt, on_event, on_status, log_);
  for (const FaultEvent& e : restored_) pipeline_->restore(e);
  listener_ =
      std::make_unique<Listener>(pipeline_.get(), mmsi, dds_->secure() ? &dds_->peers() : nullptr);
  // The vessel's own samples only (issue 14): on a partition shared by a fleet, every sidecar
  // used to receive every vessel's stream and drop the others' after their receipt.
  auto reader = [this, mmsi](dds::DdsContext& ctx, dds::TopicId id,
                             const std::string& profile) -> DataReader& {
    return cfg_.content_filter ? ctx.create_vessel_reader(id, profile, mmsi)
                               : ctx.create_reader(id, profile);
  };
  if (cfg_.input == InputSource::kNmea) {
    nmea_ = std::make_unique<NmeaInput>(cfg_.nmea, pipeline_.get(), log_);
  } else {
    listener_->ins_ = &reader(*dds_, dds::TopicId::kIns,
                              cfg_.reliable_inputs ? dds::profiles::kInsReaderReliable
                                                   : dds::profiles::kInsReaderBestEffort);
    listener_->rudder_ = &reader(*dds_, dds::TopicId::kRudder,
                                 cfg_.reliable_inputs ? dds::profiles::kRudderReaderReliable
                                                      : dds::profiles::kRudderReaderBestEffort);
    // The optional surge speed: a stream like the rudder's, with its QoS profiles. Not having
    // it is no reason to stop (DDS Security permissions signed before the topic existed
    // refuse the reader): the FDI then runs without a speed, and says so.
    try {
      listener_->speed_ = &reader(*dds_, dds::TopicId::kSpeed,
                                  cfg_.reliable_inputs ? dds::profiles::kRudderReaderReliable
                                                       : dds::profiles::kRudderReaderBestEffort);
    } catch (const std::exception& e) {
      if (log_) {
        log_(2, std::string("no reader of the surge speed (") + e.what() +
                    "): running without a speed input; under DDS Security, permissions made "
                    "before data model version 3 must be made again (scripts/make-security.sh) "
                    "to allow it");
      }
    }
  }
  // Acks are read by a participant of their own: its traffic arrives on its own port, handled
  // by its own receive thread, so a flood of acks cannot hold up (nor, through KEEP_LAST
  // histories, lose) the INS and rudder samples behind it.
  ack_dds_ = std::make_unique<dds::DdsContext>(cfg_.dds);
  DataReader& ack = reader(*ack_dds_, dds::TopicId::kFaultAck, dds::profiles::kFaultAckReader);
  listener_->ack_ = &ack;
  watch_ = std::make_unique<EventWatch>(mmsi, event_writer_->get_instance_handle(), log_);
  event_watch_ = &dds_->create_reader(dds::TopicId::kFaultEvent, dds::profiles::kFaultEventReader);
}

FdiService::~FdiService() {
  stop();
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the flock
}

bool FdiService::lock_state(const std::string& dir) {
  const std::string path =
      (std::filesystem::path(dir) / ("usv-fdi-" + std::to_string(cfg_.mmsi) + ".lock")).string();
  const auto say = [this](int level, const std::string& msg) {
    if (log_) log_(level, "state: " + msg);
  };
  const int fd =
      ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK | O_NOCTTY, 0640);
  struct stat sb {};
  if (fd < 0 || ::fstat(fd, &sb) != 0 || !S_ISREG(sb.st_mode)) {
    // Not a reason to refuse to start; the journal will say whether it can write.
    say(2, "cannot use the lock file " + path + " (" +
               (fd < 0 ? std::string(std::strerror(errno))
                       : "it is " + StateJournal::file_type(sb.st_mode)) +
               "): a second sidecar on this state directory would not be noticed");
    if (fd >= 0) ::close(fd);
    return false;
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    char pid[32] = {0};
    const ssize_t n = ::pread(fd, pid, sizeof pid - 1, 0);
    ::close(fd);
    std::string holder = n > 0 ? std::string(pid, static_cast<std::size_t>(n)) : "";
    while (!holder.empty() && (holder.back() == '\n' || holder.back() == ' ')) holder.pop_back();
    if (err == EWOULDBLOCK) {
      throw StateInUse("the state directory " + dir + " is in use by another sidecar for MMSI " +
                       std::to_string(cfg_.mmsi) +
                       (holder.empty() ? std::string() : " (pid " + holder + ")") + ", lock " +
                       path +
                       ": two sidecars for one vessel would both publish its events and race "
                       "on its state file; stop the other one, or give this one its own "
                       "--state-dir");
    }
    say(2, "cannot lock " + path + ": " + std::strerror(err) +
               ": a second sidecar on this state directory would not be noticed");
    return false;
  }
  const std::string me = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, me.data(), me.size(), 0) < 0) {
    say(2, "cannot write the pid to " + path + ": " + std::strerror(errno));
  }
  lock_fd_ = fd;
  return true;
}

void FdiService::open_journal() {
  namespace fs = std::filesystem;
  const auto say = [this](int level, const std::string& msg) {
    if (log_) log_(level, "state: " + msg);
  };
  const std::string& dir = cfg_.state_dir;
  if (dir.empty()) {
    say(2, "not persisted (no state directory): latched faults will NOT survive a restart");
    return;
  }
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    if (!cfg_.state_dir_explicit) {
      say(2, "not persisted: the default state directory " + dir +
                 " does not exist; latched faults will NOT survive a restart (set "
                 "service.state_dir or --state-dir)");
      return;
    }
    fs::create_directories(dir, ec);
    if (ec) {
      say(3, "cannot create the state directory " + dir + ": " + ec.message() +
                 "; latched faults will NOT survive a restart");
      return;
    }
    say(1, "created the state directory " + dir);
  }
  lock_state(dir);  // throws StateInUse if another sidecar has it
  const std::string path = StateJournal::path_for(dir, cfg_.mmsi);
  journal_ = std::make_unique<StateJournal>(path, cfg_.mmsi);
  fs::remove(path + ".tmp", ec);  // a save interrupted by a crash; the file itself is whole
  StateJournal::Contents c;
  std::string error;
  switch (StateJournal::load(path, cfg_.mmsi, &c, &error)) {
    case StateJournal::LoadResult::kMissing:
      say(1, "no state file " + path + " yet: nothing to restore");
      break;
    case StateJournal::LoadResult::kError: {
      std::string why;
      const std::string aside = StateJournal::set_aside(path, &why);
      say(3, "cannot restore latched faults: " + error + "; " +
                 (aside.empty() ? "could not move it aside (" + why + ")"
                                : "moved it aside to " + aside) +
                 "; starting with no latched faults");
      break;
    }
    case StateJournal::LoadResult::kLoaded: {
      restored_ = c.events;
      for (const FaultEvent& e : restored_) journal_->seed(e);
      const double now =
          std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
              .count();
      std::string list;
      for (const FaultEvent& e : restored_) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "%s #%llu %s (%s, raised at t=%.2f s)", to_string(e.sensor),
                      static_cast<unsigned long long>(e.sequence), to_string(e.state),
                      to_string(e.kind), e.detection_time);
        list += (list.empty() ? "" : "; ") + std::string(buf);
      }
      char age[64];
      std::snprintf(age, sizeof age, "%.1f s ago", now - c.written);
      say(1, "restored " + std::to_string(restored_.size()) + " fault instance(s) from " + path +
                 " (written " + utc_text(c.written) + ", " + age + ")" +
                 (restored_.empty() ? std::string()
                                    : ": " + list + "; re-published with the same sequences"));
      break;
    }
  }
  // Write it now: a directory that cannot be written is reported at start, not at the first
  // fault.
  if (!journal_->save()) {
    journal_error_logged_ = journal_->last_error();
    say(3, "cannot write the state file: " + journal_error_logged_ +
               "; latched faults will NOT survive a restart until this is fixed");
  }
}

FdiService::Matches FdiService::matches() const {
  Matches m;
  if (stopped_ || !dds_) return m;
  eprosima::fastdds::dds::SubscriptionMatchedStatus sub;
  eprosima::fastdds::dds::PublicationMatchedStatus pub;
  if (listener_->ins_ != nullptr &&
      listener_->ins_->get_subscription_matched_status(sub) == ReturnCode_t::RETCODE_OK)
    m.ins_writers = sub.current_count;
  if (listener_->rudder_ != nullptr &&
      listener_->rudder_->get_subscription_matched_status(sub) == ReturnCode_t::RETCODE_OK)
    m.rudder_writers = sub.current_count;
  if (listener_->speed_ != nullptr &&
      listener_->speed_->get_subscription_matched_status(sub) == ReturnCode_t::RETCODE_OK)
    m.speed_writers = sub.current_count;
  if (listener_->ack_->get_subscription_matched_status(sub) == ReturnCode_t::RETCODE_OK)
    m.ack_writers = sub.current_count;
  // Subscribers other than sidecars: not this sidecar's own EventWatch reader (same
  // participant, matched at once), nor those of the other sidecars on the domain. Fast DDS 2.9
  // cannot list matched readers, so the other sidecars are counted as the FaultEvent writers
  // the EventWatch reader has matched besides this sidecar's own (each sidecar has one writer
  // and one watch reader).
  if (event_writer_->get_publication_matched_status(pub) == ReturnCode_t::RETCODE_OK) {
    int others = 0;
    if (event_watch_ != nullptr &&
        event_watch_->get_subscription_matched_status(sub) == ReturnCode_t::RETCODE_OK) {
      others = std::max(0, sub.current_count - 1);
    }
    m.event_readers = std::max(0, pub.current_count - (event_watch_ != nullptr ? 1 : 0) - others);
  }
  if (status_writer_->get_publication_matched_status(pub) == ReturnCode_t::RETCODE_OK)
    m.status_readers = pub.current_count;
  return m;
}

std::uint64_t FdiService::foreign_samples() const { return listener_->foreign.load(); }
std::uint64_t FdiService::other_event_writers() const { return watch_ ? watch_->writers() : 0; }
std::uint64_t FdiService::other_event_samples() const { return watch_ ? watch_->samples() : 0; }

void FdiService::start() {
  pipeline_->start();
  // Listeners are attached only now, so nothing arrives before the threads run.
  for (DataReader* r : {listener_->ins_, listener_->rudder_, listener_->speed_, listener_->ack_}) {
    if (r != nullptr) r->set_listener(listener_.get(), StatusMask::data_available());
  }
  event_watch_->set_listener(watch_.get(), StatusMask::data_available());
  if (nmea_) {
    nmea_->start();
    if (log_) {
      char rate[96];
      std::snprintf(rate, sizeof rate, "samples at %g Hz, max age %g s%s",
                    cfg_.nmea.assembler.rate_hz, cfg_.nmea.assembler.max_age_s,
                    cfg_.nmea.assembler.hold_until_due ? ", held until the next is due" : "");
      log_(1, "NMEA input: " + nmea_->describe() + " (receive buffer " +
                  std::to_string(nmea_->receive_buffer()) + " bytes), " + rate);
    }
  }
}

void FdiService::stop() {
  if (stopped_) return;
  stopped_ = true;
  for (DataReader* r :
       {listener_->ins_, listener_->rudder_, listener_->speed_, listener_->ack_, event_watch_}) {
    if (r != nullptr) r->set_listener(nullptr);
  }
  if (nmea_) {
    nmea_->stop();  // no more samples; its status note stays readable
    if (log_) {
      const nmea_udp::DecoderStats st = nmea_->stats();
      const auto u = [](std::uint64_t x) { return std::to_string(x); };
      log_(1, "NMEA input stopped: " + u(st.datagrams) + " datagrams, " + u(st.lines) +
                  " lines: " + u(st.used) + " used (" + u(st.not_valid) + " not valid), " +
                  u(st.ignored) + " ignored, " + u(st.bad) + " refused" +
                  (st.bad > 0 ? " (" + st.describe() + ")" : std::string()) + "; " +
                  u(st.lost_lines) + " lines lost");
    }
  }
  pipeline_->stop();  // drains the queues; the publisher thread writes the last events
  if (log_ && uplink_.offered() > 0) {
    const auto n = [this](UplinkReason r) {
      return static_cast<unsigned long long>(uplink_.sent(r));
    };
    char line[256];
    std::snprintf(line, sizeof line,
                  "status uplink (%s): %llu of %llu statuses sent (first %llu, discrete %llu, "
                  "continuous %llu, heartbeat %llu)",
                  cfg_.uplink.event ? "event" : "periodic",
                  static_cast<unsigned long long>(uplink_.sent_total()),
                  static_cast<unsigned long long>(uplink_.offered()), n(UplinkReason::kFirst),
                  n(UplinkReason::kDiscrete), n(UplinkReason::kContinuous),
                  n(UplinkReason::kHeartbeat));
    log_(1, line);
  }
  ack_dds_.reset();
  dds_.reset();  // delete_contained_entities(), then the participant
}

}  // namespace usvfdi::dds_service
