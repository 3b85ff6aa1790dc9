// Benchmark of the usv-fdi DDS sidecar (issue 3), not a test: prints medians, percentiles
// and ratios measured side by side in one run.
//
//   usv_fdi_bench_dds [--faults N] [--block B] [--cpu-seconds S] [--rate HZ] [--domain D]
//                     [--participant-profile P] [--joins J] [--skip-latency] [--skip-cpu]
//                     [--skip-late-join] [--shore-vessels N,N...] [--shore-seconds S]
//                     [--skip-shore] [--fanout N,N...] [--fanout-seconds S] [--skip-fanout]
//
// 1. Latency. Two responders run as separate processes on loopback (UDPv4 127.0.0.1,
//    participant profile usv_fdi_participant_loopback), each on its own partition:
//      * the real sidecar, `usv-fdi run` (Otter engine settings; isolation.invalid_count 1,
//        spike_window 0.1 s, so one absurd INS value raises an `invalid` accelerometer fault
//        on that very sample, and 0.12 s of plausible samples clear it again);
//      * `usv_fdi_bench_dds echo`: a plain Fast DDS participant whose INS listener writes a
//        FaultEvent of the same size with the same QoS profiles, straight from the callback.
//    The driver writes rudder(t) then INS(t) with v = 1000 m/s and times the write of the INS
//    sample to the take() of the FaultEvent (state raised, stamp t) at its own reader (same
//    process, steady clock); then it writes 6 plausible samples and (sidecar) waits for the
//    clear. Faults go in interleaved blocks of B to the sidecar and to the echo so that both
//    see the same machine load. The first block of each is warm-up and not counted.
//    Reported: p50/p90/p99/max per path, and sidecar minus echo (added latency).
// 2. CPU and RSS. A fresh sidecar (default Otter settings) and a fresh echo both subscribe to
//    one stream of simulated Otter data (autopilot, realistic noise) at HZ (default 100) in
//    real time. CPU = (utime+stime) over S seconds after a 5 s warm-up, from /proc/<pid>/stat;
//    RSS = VmRSS at the end and VmHWM, from /proc/<pid>/status.
//
// 3. Late join. Three `usv_fdi_bench_dds latched` processes each hold the latched state of one
//    vessel (two FaultEvent instances and one FdiStatus, written once), each on its own
//    partition: with the shipped profiles; with Fast DDS's default participant announcement
//    period (3 s); with that and the default writer heartbeat period (3 s), as shipped before.
//    The driver joins each in turn JOINS times: a new participant with the monitor's reader
//    profiles, timed from the readers' creation to their match and to the take of all three
//    latched samples.
//
// 4. Shore at fleet scale. For each N of --shore-vessels: a Fast DDS
//    discovery server on 127.0.0.1 and, as its clients (the documented fleet configuration:
//    docker/fleet_participants.xml, profile usv_fdi_fleet_udp, ROS_DISCOVERY_SERVER), a
//    `usv-fdi monitor --json --status` and `usv-fdi emulate --vessels N` (N vessels on
//    min(N, 10) participants, or P with N/P in the list (default 100,1000,1000/100), FdiStatus at 1
//    Hz each, 5 fault events/s and a burst of N/10 simultaneous raises every 10 s). Reported: the
//    time from the emulator's start until the monitor has shown every vessel; then over
//    --shore-seconds: the monitor's CPU and RSS, and the fault event to printed line latency (the
//    monitor's own `age_s`: wall clock at the print minus the event's write time) p50/p99/max,
//    bursts included.
//
// 5. Input fan-out. For each N of --fanout (default 5,10,20,40): N sidecars (one MMSI each)
//    and one `usv-fdi sim --publish` of N healthy Otter voyages at 10 Hz in real time, all on
//    one partition and clients of a discovery server (as in part 4); the sidecars' CPU over
//    --fanout-seconds (from 5 s after the simulator starts publishing), with
//    service.content_filter false (every sidecar receives every vessel's stream and drops the
//    others') and true (the shipped default), one after the other.
//
// Exit code 0 when it completed (targets are reported, not enforced), 1 on error.
#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/dds/dds_context.hpp"

extern char** environ;

namespace {

namespace dds = usvfdi::dds;
namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;
using Clock = std::chrono::steady_clock;

constexpr std::uint32_t kMmsi = 257999001;
constexpr double kAbsurd = 1000.0;  // [m/s] > isolation.max_abs_v
const char* const kInvalidMessage = "accelerometer channel v: repeated non-finite or absurd values";

struct Options {
  int faults = 1000;
  int block = 50;
  double cpu_seconds = 60.0;
  double rate = 100.0;
  std::uint32_t domain = 1 + static_cast<std::uint32_t>(::getpid()) % 200;
  std::string participant = dds::profiles::kParticipantLoopback;
  bool latency = true;
  bool cpu = true;
  bool late_join = true;
  int joins = 40;
  // echo and latched modes
  std::string partition;
  bool shore = true;
  bool fanout = true;
  std::vector<int> fanout_sidecars{5, 10, 20, 40};
  double fanout_seconds = 20.0;
  std::vector<int> shore_vessels{100, 1000, 1000};
  std::vector<int> shore_participants{0, 0, 100};  ///< 0: the emulator's default
  double shore_seconds = 30.0;
  int heartbeat_ms = 0;  ///< latched mode: 0 keeps the writer profiles' heartbeat period
  std::string profiles = USV_FDI_QOS_PROFILES;
};

dds::DdsConfig dds_config(const Options& o, const std::string& partition) {
  dds::DdsConfig c;
  c.profiles_file = o.profiles;
  c.domain_id = o.domain;
  c.participant_profile = o.participant;
  c.publisher_partitions = {partition};
  c.subscriber_partitions = {partition};
  return c;
}

// ------------------------------------------------------------------ echo (plain DDS)

/// Writes a raised FaultEvent for an absurd INS value and a cleared one for the first plausible
/// sample after it, from the listener callback: the plain Fast DDS round trip.
class Echo : public fdds::DataReaderListener {
 public:
  explicit Echo(fdds::DataWriter* w) : w_(w) {}
  void on_data_available(fdds::DataReader* r) override {
    fdi::InsSample s;
    fdds::SampleInfo info;
    while (r->take_next_sample(&s, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      const bool absurd = std::abs(s.v()) > 20.0;
      if (!absurd && !raised_) continue;
      fdi::FaultEvent e;
      e.mmsi(s.mmsi());
      e.sensor(0);
      e.state(absurd ? 1 : 3);
      e.kind(8);
      e.detection_time(s.stamp());
      e.onset_time(s.stamp());
      e.stamp(s.stamp());
      e.sequence(++seq_);
      e.message(kInvalidMessage);
      raised_ = absurd;
      dds::write(*w_, e);
    }
  }

 private:
  fdds::DataWriter* w_;
  bool raised_ = false;  // one INS reader: Fast DDS serialises its callbacks per reader
  std::uint64_t seq_ = 0;
};

int run_echo(const Options& o) {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  dds::DdsContext ctx(dds_config(o, o.partition));
  fdds::DataWriter& w =
      ctx.create_writer(dds::TopicId::kFaultEvent, dds::profiles::kFaultEventWriter);
  Echo echo(&w);
  ctx.create_reader(dds::TopicId::kRudder, dds::profiles::kRudderReaderBestEffort);
  ctx.create_reader(dds::TopicId::kIns, dds::profiles::kInsReaderBestEffort, &echo,
                    fdds::StatusMask::data_available());
  std::printf("echo ready\n");
  std::fflush(stdout);
  int sig = 0;
  while (sig <= 0) {
    timespec ts{1, 0};
    sig = sigtimedwait(&set, nullptr, &ts);
  }
  return 0;
}

// ------------------------------------------------------------------ latched (plain DDS)

/// A writer from `profile`, with the heartbeat period overridden when heartbeat_ms > 0.
fdds::DataWriter& latched_writer(dds::DdsContext& ctx, dds::TopicId topic, const char* profile,
                                 int heartbeat_ms) {
  if (heartbeat_ms <= 0) return ctx.create_writer(topic, profile);
  fdds::DataWriterQos q;
  if (ctx.publisher().get_datawriter_qos_from_profile(profile, q) != ReturnCode_t::RETCODE_OK) {
    throw std::runtime_error(std::string("no data writer profile ") + profile);
  }
  q.reliable_writer_qos().times.heartbeatPeriod =
      eprosima::fastrtps::Duration_t(heartbeat_ms / 1000, (heartbeat_ms % 1000) * 1000000u);
  fdds::DataWriter* w = ctx.publisher().create_datawriter(&ctx.topic(topic), q);
  if (w == nullptr) throw std::runtime_error(std::string("cannot create writer ") + profile);
  return *w;
}

/// Holds one vessel's latched state: a raised accelerometer and a raised gyro FaultEvent and
/// one FdiStatus, written once, until a signal.
int run_latched(const Options& o) {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  dds::DdsContext ctx(dds_config(o, o.partition));
  fdds::DataWriter& ev = latched_writer(ctx, dds::TopicId::kFaultEvent,
                                        dds::profiles::kFaultEventWriter, o.heartbeat_ms);
  fdds::DataWriter& st =
      latched_writer(ctx, dds::TopicId::kStatus, dds::profiles::kStatusWriter, o.heartbeat_ms);
  for (std::uint8_t sensor = 0; sensor < 2; ++sensor) {
    fdi::FaultEvent e;
    e.mmsi(kMmsi);
    e.sensor(sensor);
    e.state(1);
    e.kind(1);
    e.sequence(1);
    e.stamp(100.0);
    dds::write(ev, e);
  }
  fdi::FdiStatus s;
  s.mmsi(kMmsi);
  s.stamp(100.0);
  dds::write(st, s);
  std::printf("latched ready\n");
  std::fflush(stdout);
  int sig = 0;
  while (sig <= 0) {
    timespec ts{1, 0};
    sig = sigtimedwait(&set, nullptr, &ts);
  }
  return 0;
}

// ------------------------------------------------------------------ child processes

class Child {
 public:
  explicit Child(const std::vector<std::string>& argv, const std::string& log) {
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    const pid_t parent = ::getpid();
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("cannot fork for " + argv[0]);
    if (pid_ == 0) {
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlive the benchmark
      if (::getppid() != parent) ::_exit(127);
      const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd >= 0) {
        ::dup2(fd, STDOUT_FILENO);
        ::dup2(fd, STDERR_FILENO);
      }
      ::execve(args[0], args.data(), environ);
      ::_exit(127);
    }
  }
  ~Child() { stop(); }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  pid_t pid() const { return pid_; }
  /// SIGTERM, then SIGKILL after 3 s.
  void stop() {
    if (pid_ <= 0) return;
    ::kill(pid_, SIGTERM);
    int status = 0;
    for (int i = 0; i < 300; ++i) {
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
  }

 private:
  pid_t pid_ = -1;
};

std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::ostringstream os;
  os << f.rdbuf();
  return os.str();
}

bool wait_for_text(const std::string& path, const std::string& text, double seconds) {
  const auto end = Clock::now() + std::chrono::duration<double>(seconds);
  while (Clock::now() < end) {
    if (slurp(path).find(text) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

struct ProcUsage {
  double cpu_s = 0;  ///< utime + stime [s]
  double rss_mb = 0, hwm_mb = 0;
};

ProcUsage usage(pid_t pid) {
  ProcUsage u;
  {
    std::ifstream f("/proc/" + std::to_string(pid) + "/stat");
    std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    const auto close = text.rfind(')');  // comm may contain spaces
    std::istringstream in(text.substr(close + 2));
    std::string field;
    std::vector<std::string> fields;
    while (in >> field) fields.push_back(field);
    // fields[0] is field 3 (state); utime = field 14, stime = field 15.
    if (fields.size() > 13) {
      u.cpu_s = (std::stod(fields[11]) + std::stod(fields[12])) /
                static_cast<double>(sysconf(_SC_CLK_TCK));
    }
  }
  std::ifstream f("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(f, line);) {
    if (line.rfind("VmRSS:", 0) == 0) u.rss_mb = std::stod(line.substr(6)) / 1024.0;
    if (line.rfind("VmHWM:", 0) == 0) u.hwm_mb = std::stod(line.substr(6)) / 1024.0;
  }
  return u;
}

// ------------------------------------------------------------------ driver side

/// INS + rudder writers and a FaultEvent reader on one partition.
class Endpoint {
 public:
  Endpoint(const Options& o, const std::string& partition)
      : ctx_(std::make_unique<dds::DdsContext>(dds_config(o, partition))) {
    ins_ = &ctx_->create_writer(dds::TopicId::kIns, dds::profiles::kInsWriterBestEffort);
    rud_ = &ctx_->create_writer(dds::TopicId::kRudder, dds::profiles::kRudderWriterBestEffort);
    ev_ = &ctx_->create_reader(dds::TopicId::kFaultEvent, dds::profiles::kFaultEventReader);
    ev_->get_statuscondition().set_enabled_statuses(fdds::StatusMask::data_available());
    ws_.attach_condition(ev_->get_statuscondition());
  }

  bool matched(double seconds) {
    const auto end = Clock::now() + std::chrono::duration<double>(seconds);
    while (Clock::now() < end) {
      fdds::PublicationMatchedStatus a, b;
      fdds::SubscriptionMatchedStatus c;
      ins_->get_publication_matched_status(a);
      rud_->get_publication_matched_status(b);
      ev_->get_subscription_matched_status(c);
      if (a.current_count > 0 && b.current_count > 0 && c.current_count > 0) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  }

  /// Writes rudder(t) then INS(t); returns the time just before the INS write.
  Clock::time_point write(double t, double v, double r, double delta) {
    fdi::RudderSample d;
    d.mmsi(kMmsi);
    d.seq(++seq_);
    d.stamp(t);
    d.delta(delta);
    d.valid(true);
    dds::write(*rud_, d);
    fdi::InsSample s;
    s.mmsi(kMmsi);
    s.seq(seq_);
    s.stamp(t);
    s.v(v);
    s.r(r);
    s.v_valid(true);
    s.r_valid(true);
    const auto t0 = Clock::now();
    dds::write(*ins_, s);
    return t0;
  }

  /// Waits for a FaultEvent with this state and stamp; returns its receipt time.
  bool wait_event(std::uint8_t state, double stamp, double timeout_s, Clock::time_point* at) {
    const auto end = Clock::now() + std::chrono::duration<double>(timeout_s);
    fdi::FaultEvent e;
    fdds::SampleInfo info;
    for (;;) {
      while (ev_->take_next_sample(&e, &info) == ReturnCode_t::RETCODE_OK) {
        if (info.valid_data && e.state() == state && (stamp < 0 || e.stamp() == stamp)) {
          *at = Clock::now();
          return true;
        }
      }
      const auto left = std::chrono::duration<double>(end - Clock::now()).count();
      if (left <= 0) return false;
      fdds::ConditionSeq active;
      ws_.wait(active, eprosima::fastrtps::Duration_t(std::min(left, 0.5)));
    }
  }

  void drain() {
    fdi::FaultEvent e;
    fdds::SampleInfo info;
    while (ev_->take_next_sample(&e, &info) == ReturnCode_t::RETCODE_OK) {
    }
  }

 private:
  std::unique_ptr<dds::DdsContext> ctx_;
  fdds::DataWriter *ins_ = nullptr, *rud_ = nullptr;
  fdds::DataReader* ev_ = nullptr;
  fdds::WaitSet ws_;
  std::uint64_t seq_ = 0;
};

/// Plausible Otter data (autopilot, realistic noise), endless.
class Voyage {
 public:
  explicit Voyage(double rate) {
    usvfdi::VesselModel v;
    if (!usvfdi::find_vessel("otter", &v)) throw std::runtime_error("no otter model");
    usvfdi::SimConfig c;
    c.vessel = v;
    c.rate_hz = rate;
    c.duration = 1e9;
    c.steering = usvfdi::Steering::kAutopilot;
    sim_ = std::make_unique<usvfdi::Simulator>(c);
  }
  usvfdi::SimRow next() {
    usvfdi::SimRow r;
    sim_->next(&r);
    return r;
  }

 private:
  std::unique_ptr<usvfdi::Simulator> sim_;
};

double pct(std::vector<double> x, double p) {
  if (x.empty()) return NAN;
  std::sort(x.begin(), x.end());
  const double k = p / 100.0 * static_cast<double>(x.size() - 1);
  const auto i = static_cast<std::size_t>(std::floor(k));
  const double f = k - static_cast<double>(i);
  return i + 1 < x.size() ? x[i] * (1 - f) + x[i + 1] * f : x[i];
}

/// The sidecar's config: the Otter's engine settings (config/vessels/otter.yaml) and a service
/// section. For the latency run, isolation.invalid_count 1 and spike_window 0.1 s make one
/// absurd value raise an `invalid` fault at once and 0.1 s of plausible values clear it.
std::string write_service_config(const std::string& dir, const std::string& name,
                                 bool invalid_raises_at_once, std::uint32_t mmsi = kMmsi,
                                 const std::string& extra = "") {
  const std::string path = dir + "/" + name + ".yaml";
  std::ofstream f(path);
  std::string otter = slurp(std::string(USV_FDI_SOURCE_DIR) + "/config/vessels/otter.yaml");
  if (invalid_raises_at_once) {
    const auto at = otter.find("isolation:\n");
    if (at == std::string::npos) throw std::runtime_error("otter.yaml has no isolation section");
    otter.insert(at + 11, "  invalid_count: 1\n  spike_window: 0.1\n");
  }
  f << otter << "\nservice:\n  mmsi: " << mmsi << "\n  status_rate: 1\n" << extra;
  if (invalid_raises_at_once) f << "  input_timeout: 60\n";
  if (!f) throw std::runtime_error("cannot write " + path);
  return path;
}

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

/// Where and how the driver starts its responders: the options, this executable (the echo),
/// the log directory and a tag that keeps this run's partitions apart from any other's.
struct Driver {
  const Options& o;
  std::string self;
  std::string dir;
  std::string tag;

  /// A responder's command line: head, then the domain, partition and participant profile.
  std::vector<std::string> command(std::vector<std::string> head,
                                   const std::string& partition) const {
    for (const std::string& a :
         {std::string("--domain"), std::to_string(o.domain), std::string("--partition"), partition,
          std::string("--participant-profile"), o.participant}) {
      head.push_back(a);
    }
    return head;
  }
};

/// The two responders of one part of the benchmark, `name`: the sidecar (`usv-fdi run` with
/// write_service_config) and the echo, logging to <dir>/<name>_sidecar.log and _echo.log.
struct Responders {
  Responders(const Driver& d, const std::string& name, const std::string& svc_partition,
             const std::string& echo_partition, bool invalid_raises_at_once)
      : sidecar(d.command({USV_FDI_EXE, "run", "--config",
                           write_service_config(d.dir, name, invalid_raises_at_once)},
                          svc_partition),
                d.dir + "/" + name + "_sidecar.log"),
        echo(d.command({d.self, "echo"}, echo_partition), d.dir + "/" + name + "_echo.log") {}

  /// Whether both said they are ready within 15 s (a message on stderr if not).
  static bool started(const Driver& d, const std::string& name) {
    if (!wait_for_text(d.dir + "/" + name + "_sidecar.log", "waiting for INS", 15) ||
        !wait_for_text(d.dir + "/" + name + "_echo.log", "echo ready", 15)) {
      std::fprintf(stderr, "responders did not start; see %s\n", d.dir.c_str());
      return false;
    }
    return true;
  }

  Child sidecar;
  Child echo;
};

/// One path of the latency run: the endpoint to its responder, its data time, the measured
/// latencies [us] and the faults whose events did not come.
struct LatencyPath {
  LatencyPath(const Options& o, const std::string& partition, bool is_sidecar)
      : ep(o, partition), sidecar(is_sidecar) {}
  Endpoint ep;
  bool sidecar;  ///< the sidecar clears the fault itself; the echo's events are drained
  double t = 0.0;
  std::vector<double> latency_us;
  int lost = 0;
};

/// `block` faults: an absurd INS value, the raised event timed (kept when count), then 0.12 s
/// of plausible data and, from the sidecar, its cleared event.
void run_fault_block(LatencyPath* path, Voyage* voyage, int block, bool count) {
  Endpoint& ep = path->ep;
  for (int k = 0; k < block; ++k) {
    usvfdi::SimRow row = voyage->next();
    path->t += 0.02;
    const auto t0 = ep.write(path->t, kAbsurd, row.r, row.delta);
    Clock::time_point t1;
    if (ep.wait_event(1, path->t, 2.0, &t1)) {
      if (count) {
        path->latency_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
      }
    } else {
      ++path->lost;
    }
    for (int j = 0; j < 6; ++j) {  // 0.12 s of plausible data clears the fault
      row = voyage->next();
      path->t += 0.02;
      ep.write(path->t, row.v, row.r, row.delta);
    }
    if (path->sidecar) {
      Clock::time_point ignored;
      if (!ep.wait_event(3, -1, 2.0, &ignored)) ++path->lost;
    } else {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      ep.drain();
    }
  }
}

void print_latency(const LatencyPath& svc_path, const LatencyPath& echo_path, int block,
                   double took) {
  const std::vector<double>& svc = svc_path.latency_us;
  const std::vector<double>& echo = echo_path.latency_us;
  std::printf("\n1. End-to-end latency, INS sample write -> FaultEvent take at the subscriber\n");
  std::printf(
      "   (%zu faults per path in interleaved blocks of %d, %.1f s; not received: "
      "sidecar %d, echo %d)\n",
      svc.size(), block, took, svc_path.lost, echo_path.lost);
  std::printf("   %-34s %9s %9s %9s %9s\n", "path [us]", "p50", "p90", "p99", "max");
  std::printf("   %-34s %9.1f %9.1f %9.1f %9.1f\n", "usv-fdi run (sidecar)", pct(svc, 50),
              pct(svc, 90), pct(svc, 99), pct(svc, 100));
  std::printf("   %-34s %9.1f %9.1f %9.1f %9.1f\n", "plain Fast DDS echo (listener)", pct(echo, 50),
              pct(echo, 90), pct(echo, 99), pct(echo, 100));
  std::printf("   %-34s %9.1f %9.1f %9.1f\n", "added by the sidecar", pct(svc, 50) - pct(echo, 50),
              pct(svc, 90) - pct(echo, 90), pct(svc, 99) - pct(echo, 99));
  std::printf("   ratio sidecar/echo: p50 %.2f, p99 %.2f; target: added p99 <= 200 us: %s\n",
              pct(svc, 50) / pct(echo, 50), pct(svc, 99) / pct(echo, 99),
              pct(svc, 99) - pct(echo, 99) <= 200.0 ? "met" : "NOT met");
  std::fflush(stdout);
}

/// Part 1: faults in interleaved blocks to the sidecar and the echo, each on its partition.
int run_latency(const Driver& d) {
  const Options& o = d.o;
  const std::string p_svc = "bench_svc_" + d.tag, p_echo = "bench_echo_" + d.tag;
  Responders responders(d, "latency", p_svc, p_echo, true);
  if (!Responders::started(d, "latency")) return 1;
  LatencyPath to_svc(o, p_svc, true), to_echo(o, p_echo, false);
  if (!to_svc.ep.matched(15) || !to_echo.ep.matched(15)) {
    std::fprintf(stderr, "no match with the responders; see %s\n", d.dir.c_str());
    return 1;
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  Voyage voyage(50.0);
  run_fault_block(&to_svc, &voyage, o.block, false);  // warm-up
  run_fault_block(&to_echo, &voyage, o.block, false);
  const auto t_start = Clock::now();
  while (static_cast<int>(to_svc.latency_us.size()) < o.faults ||
         static_cast<int>(to_echo.latency_us.size()) < o.faults) {
    run_fault_block(&to_svc, &voyage, o.block, true);
    run_fault_block(&to_echo, &voyage, o.block, true);
    if (to_svc.lost + to_echo.lost > o.faults / 10) {
      std::fprintf(stderr, "too many lost faults (sidecar %d, echo %d); see %s\n", to_svc.lost,
                   to_echo.lost, d.dir.c_str());
      return 1;
    }
  }
  const double took = std::chrono::duration<double>(Clock::now() - t_start).count();
  print_latency(to_svc, to_echo, o.block, took);
  return 0;
}

/// The usage of both responders when the measurement began, its start, and the samples
/// written in all.
struct Feed {
  ProcUsage svc0{}, echo0{};
  Clock::time_point t_meas;
  std::uint64_t written = 0;
};

/// Writes the voyage in real time at o.rate for the warm-up and then o.cpu_seconds, taking
/// the responders' usage when the warm-up ends.
Feed feed_in_real_time(const Options& o, Endpoint* ep, const Responders& responders,
                       double warmup) {
  Voyage voyage(o.rate);
  const auto t0 = Clock::now();
  Feed f;
  bool started = false;
  std::uint64_t& k = f.written;
  for (;;) {
    const double t = static_cast<double>(k) / o.rate;
    std::this_thread::sleep_until(
        t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(t)));
    if (!started && t >= warmup) {
      f.svc0 = usage(responders.sidecar.pid());
      f.echo0 = usage(responders.echo.pid());
      f.t_meas = Clock::now();
      started = true;
    }
    if (t >= warmup + o.cpu_seconds) break;
    const usvfdi::SimRow r = voyage.next();
    ep->write(r.t, r.v, r.r, r.delta);
    ++k;
  }
  return f;
}

/// Part 2: one stream in real time to a fresh sidecar and a fresh echo on one partition.
int run_cpu(const Driver& d) {
  const Options& o = d.o;
  const std::string part = "bench_cpu_" + d.tag;
  Responders responders(d, "cpu", part, part, false);
  if (!Responders::started(d, "cpu")) return 1;
  Endpoint ep(o, part);
  if (!ep.matched(15)) {
    std::fprintf(stderr, "no match with the responders; see %s\n", d.dir.c_str());
    return 1;
  }
  const double warmup = 5.0;
  const Feed f = feed_in_real_time(o, &ep, responders, warmup);
  const double wall = std::chrono::duration<double>(Clock::now() - f.t_meas).count();
  const ProcUsage s0 = f.svc0, e0 = f.echo0;
  const ProcUsage s1 = usage(responders.sidecar.pid()), e1 = usage(responders.echo.pid());
  const std::string svc_log = slurp(d.dir + "/cpu_sidecar.log");
  std::printf(
      "\n2. Resources at %.0f Hz INS + rudder input (Otter, autopilot, realistic noise), "
      "%.0f s after %.0f s warm-up\n",
      o.rate, wall, warmup);
  std::printf("   %-34s %9s %9s %9s\n", "process", "CPU [%]", "RSS [MB]", "HWM [MB]");
  std::printf("   %-34s %9.2f %9.1f %9.1f\n", "usv-fdi run (sidecar)",
              100.0 * (s1.cpu_s - s0.cpu_s) / wall, s1.rss_mb, s1.hwm_mb);
  std::printf("   %-34s %9.2f %9.1f %9.1f\n", "plain Fast DDS echo (same stream)",
              100.0 * (e1.cpu_s - e0.cpu_s) / wall, e1.rss_mb, e1.hwm_mb);
  std::printf(
      "   sidecar/echo: CPU %.2f, RSS %.2f; targets < 2 %% of a core: %s, < 40 MB RSS: "
      "%s\n",
      (s1.cpu_s - s0.cpu_s) / std::max(1e-9, e1.cpu_s - e0.cpu_s), s1.rss_mb / e1.rss_mb,
      100.0 * (s1.cpu_s - s0.cpu_s) / wall < 2.0 ? "met" : "NOT met",
      s1.hwm_mb < 40.0 ? "met" : "NOT met");
  std::printf("   (%llu samples written; the sidecar raised %zu fault events)\n",
              static_cast<unsigned long long>(f.written), count_of(svc_log, "fault event MMSI"));
  return 0;
}

/// One late join: a fresh participant with the monitor's FaultEvent and FdiStatus readers on
/// `partition`; the time [s] from the readers' creation to their match and to the take of the
/// three latched samples (false when they did not all come within 10 s).
bool late_join(const Options& o, const std::string& partition, double* to_match, double* to_state) {
  dds::DdsContext ctx(dds_config(o, partition));
  const auto t0 = Clock::now();
  fdds::DataReader& ev =
      ctx.create_reader(dds::TopicId::kFaultEvent, dds::profiles::kFaultEventReader);
  fdds::DataReader& st = ctx.create_reader(dds::TopicId::kStatus, dds::profiles::kStatusReader);
  const auto end = t0 + std::chrono::seconds(10);
  bool matched = false;
  int events = 0, statuses = 0;
  *to_match = NAN;
  while (Clock::now() < end) {
    if (!matched) {
      fdds::SubscriptionMatchedStatus a, b;
      ev.get_subscription_matched_status(a);
      st.get_subscription_matched_status(b);
      if (a.current_count > 0 && b.current_count > 0) {
        matched = true;
        *to_match = std::chrono::duration<double>(Clock::now() - t0).count();
      }
    }
    fdi::FaultEvent e;
    fdi::FdiStatus s;
    fdds::SampleInfo info;
    while (ev.take_next_sample(&e, &info) == ReturnCode_t::RETCODE_OK) events += info.valid_data;
    while (st.take_next_sample(&s, &info) == ReturnCode_t::RETCODE_OK) statuses += info.valid_data;
    if (events >= 2 && statuses >= 1) {
      *to_state = std::chrono::duration<double>(Clock::now() - t0).count();
      return matched;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return false;
}

/// The shipped profiles file without its participants' announcement periods
/// (<leaseAnnouncement>): Fast DDS's default of 3 s.
std::string profiles_with_default_announcements(const Driver& d) {
  std::string xml = slurp(d.o.profiles);
  const std::string open = "<leaseAnnouncement>", close = "</leaseAnnouncement>";
  for (auto at = xml.find(open); at != std::string::npos; at = xml.find(open)) {
    const auto end = xml.find(close, at);
    if (end == std::string::npos) throw std::runtime_error("unterminated " + open);
    xml.erase(at, end + close.size() - at);
  }
  const std::string path = d.dir + "/profiles_default_announcements.xml";
  std::ofstream(path) << xml;
  return path;
}

/// One writer set-up of the late-join run and what its joins measured [s].
struct LateJoinVariant {
  const char* name;
  std::vector<std::string> args;  ///< after `latched`
  std::string partition;
  std::unique_ptr<Child> child;
  std::vector<double> to_match, to_state;
  int failed = 0;
};

/// Part 3: late joins, in turn, to the latched state of writers with the shipped profiles,
/// with Fast DDS's default participant announcement period (3 s), and with that and the
/// default writer heartbeat period (3 s): the profiles before the late-join change.
int run_late_join(const Driver& d) {
  const Options& o = d.o;
  const std::string defaults = profiles_with_default_announcements(d);
  std::vector<LateJoinVariant> v;
  v.push_back({"shipped profiles", {}, "bench_join_shipped_" + d.tag, nullptr, {}, {}, 0});
  v.push_back({"announcements 3 s",
               {"--profiles", defaults},
               "bench_join_ann_" + d.tag,
               nullptr,
               {},
               {},
               0});
  v.push_back({"announcements 3 s, heartbeat 3 s",
               {"--profiles", defaults, "--heartbeat-ms", "3000"},
               "bench_join_both_" + d.tag,
               nullptr,
               {},
               {},
               0});
  for (std::size_t k = 0; k < v.size(); ++k) {
    std::vector<std::string> head{d.self, "latched"};
    head.insert(head.end(), v[k].args.begin(), v[k].args.end());
    v[k].child = std::make_unique<Child>(d.command(head, v[k].partition),
                                         d.dir + "/latched_" + std::to_string(k) + ".log");
  }
  for (std::size_t k = 0; k < v.size(); ++k) {
    if (!wait_for_text(d.dir + "/latched_" + std::to_string(k) + ".log", "latched ready", 15)) {
      std::fprintf(stderr, "latched writers did not start; see %s\n", d.dir.c_str());
      return 1;
    }
  }
  for (int j = 0; j < o.joins; ++j) {
    for (LateJoinVariant& x : v) {
      double m = 0, t = 0;
      if (late_join(o, x.partition, &m, &t)) {
        x.to_match.push_back(m);
        x.to_state.push_back(t);
      } else {
        ++x.failed;
      }
    }
  }
  std::printf(
      "\n3. Late join: a new participant's FaultEvent + FdiStatus readers until the latched "
      "state\n   (2 events + 1 status) is taken; %d joins per writer set-up, in turn\n",
      o.joins);
  std::printf("   %-34s %22s %22s %6s\n", "", "join -> match [ms]", "join -> state [ms]", "");
  std::printf("   %-34s %7s %7s %7s %7s %7s %7s %6s\n", "writers", "p50", "p90", "max", "p50",
              "p90", "max", "failed");
  for (const LateJoinVariant& x : v) {
    std::printf("   %-34s %7.1f %7.1f %7.1f %7.1f %7.1f %7.1f %6d\n", x.name,
                1e3 * pct(x.to_match, 50), 1e3 * pct(x.to_match, 90), 1e3 * pct(x.to_match, 100),
                1e3 * pct(x.to_state, 50), 1e3 * pct(x.to_state, 90), 1e3 * pct(x.to_state, 100),
                x.failed);
  }
  std::printf("   join -> state, before (3 s, 3 s) / shipped: p50 %.2f, p90 %.2f\n",
              pct(v[2].to_state, 50) / pct(v[0].to_state, 50),
              pct(v[2].to_state, 90) / pct(v[0].to_state, 90));
  std::fflush(stdout);
  return 0;
}

/// One monitor --json line: its type, vessel and, for a fault, its age_s [s].
struct MonitorLine {
  bool fault = false;
  std::uint32_t mmsi = 0;
  double age_s = NAN;
};

bool parse_monitor_line(const std::string& line, MonitorLine* out) {
  const auto mmsi = line.find("\"mmsi\":");
  if (line.rfind("{\"type\":", 0) != 0 || mmsi == std::string::npos) return false;
  out->fault = line.rfind("{\"type\":\"fault\"", 0) == 0;
  out->mmsi = static_cast<std::uint32_t>(std::strtoul(line.c_str() + mmsi + 7, nullptr, 10));
  const auto age = line.find("\"age_s\":");
  out->age_s = age == std::string::npos ? NAN : std::strtod(line.c_str() + age + 8, nullptr);
  return true;
}

/// Reads the complete lines appended to a file since the last call.
class LineTail {
 public:
  explicit LineTail(std::string path) : path_(std::move(path)) {}
  std::vector<std::string> next() {
    std::ifstream f(path_, std::ios::binary);
    f.seekg(static_cast<std::streamoff>(offset_));
    std::string chunk((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    std::vector<std::string> lines;
    std::size_t start = 0;
    for (auto nl = chunk.find('\n'); nl != std::string::npos; nl = chunk.find('\n', start)) {
      lines.push_back(chunk.substr(start, nl - start));
      start = nl + 1;
    }
    offset_ += start;
    return lines;
  }

 private:
  std::string path_;
  std::size_t offset_ = 0;
};

/// Part 4 for one fleet size: discovery time, monitor CPU/RSS, event latency.
/// The documented fleet configuration on 127.0.0.1: a Fast DDS discovery server (profile
/// usv_fdi_discovery_server_udp of docker/fleet_participants.xml) and, while it lives, the
/// environment that makes the children started meanwhile its clients (ROS_DISCOVERY_SERVER,
/// that file as FASTRTPS_DEFAULT_PROFILES_FILE); args() are their DDS options.
class FleetDiscovery {
 public:
  FleetDiscovery(const Driver& d, const std::string& tag, int port, const std::string& partition)
      : d_(d), partition_(partition) {
    // The server must not see ROS_DISCOVERY_SERVER (the 2.9 server then aborts).
    clear_env();
    server_ = std::make_unique<Child>(
        std::vector<std::string>{"/usr/bin/fast-discovery-server", "-i", "0", "-l", "127.0.0.1",
                                 "-p", std::to_string(port), "-x",
                                 "usv_fdi_discovery_server_udp@" + xml()},
        d.dir + "/" + tag + "_server.log");
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    ::setenv("ROS_DISCOVERY_SERVER", ("127.0.0.1:" + std::to_string(port)).c_str(), 1);
    ::setenv("FASTRTPS_DEFAULT_PROFILES_FILE", xml().c_str(), 1);
  }
  ~FleetDiscovery() { clear_env(); }
  FleetDiscovery(const FleetDiscovery&) = delete;
  FleetDiscovery& operator=(const FleetDiscovery&) = delete;
  std::vector<std::string> args() const {
    return {"--domain",
            std::to_string(d_.o.domain),
            "--qos",
            d_.o.profiles,
            "--participant-profile",
            "usv_fdi_fleet_udp",
            "--partition",
            partition_};
  }

 private:
  static std::string xml() {
    return std::string(USV_FDI_SOURCE_DIR) + "/docker/fleet_participants.xml";
  }
  static void clear_env() {
    ::unsetenv("ROS_DISCOVERY_SERVER");
    ::unsetenv("FASTRTPS_DEFAULT_PROFILES_FILE");
  }
  const Driver& d_;
  std::string partition_;
  std::unique_ptr<Child> server_;
};

int run_shore_one(const Driver& d, int vessels, int participants, int port) {
  const Options& o = d.o;
  const std::string tag = "shore" + std::to_string(vessels);
  FleetDiscovery fleet(d, tag, port, "bench_shore_" + d.tag);
  const std::vector<std::string> dds_args = fleet.args();
  std::vector<std::string> mon = {USV_FDI_EXE, "monitor", "--json", "--status"};
  mon.insert(mon.end(), dds_args.begin(), dds_args.end());
  const std::string mon_out = d.dir + "/" + tag + "_monitor.jsonl";
  Child monitor(mon, mon_out);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const int burst = std::max(1, vessels / 10);
  std::vector<std::string> emu = {USV_FDI_EXE,     "emulate", "--vessels", std::to_string(vessels),
                                  "--event-rate",  "5",       "--burst",   std::to_string(burst),
                                  "--burst-every", "10"};
  if (participants > 0) {
    emu.push_back("--participants");
    emu.push_back(std::to_string(participants));
  }
  emu.insert(emu.end(), dds_args.begin(), dds_args.end());
  const auto t_start = Clock::now();
  Child emulator(emu, d.dir + "/" + tag + "_emulate.log");
  LineTail tail(mon_out);
  std::set<std::uint32_t> seen;
  double discovery_s = NAN;
  const auto discovery_deadline = t_start + std::chrono::seconds(120);
  while (Clock::now() < discovery_deadline) {
    for (const std::string& l : tail.next()) {
      MonitorLine m;
      if (parse_monitor_line(l, &m)) seen.insert(m.mmsi);
    }
    if (static_cast<int>(seen.size()) >= vessels) {
      discovery_s = std::chrono::duration<double>(Clock::now() - t_start).count();
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const ProcUsage u0 = usage(monitor.pid()), e0 = usage(emulator.pid());
  const auto t_meas = Clock::now();
  std::vector<double> latency;
  std::size_t lines = 0;
  const auto t_end = t_meas + std::chrono::duration_cast<Clock::duration>(
                                  std::chrono::duration<double>(o.shore_seconds));
  while (Clock::now() < t_end) {
    for (const std::string& l : tail.next()) {
      MonitorLine m;
      if (!parse_monitor_line(l, &m)) continue;
      ++lines;
      seen.insert(m.mmsi);
      if (m.fault && std::isfinite(m.age_s)) latency.push_back(m.age_s);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  const double wall = std::chrono::duration<double>(Clock::now() - t_meas).count();
  const ProcUsage u1 = usage(monitor.pid()), e1 = usage(emulator.pid());
  const int parts = participants > 0 ? participants : std::min(vessels, 10);
  std::printf("   %5d/%-4d %9.2f %7zu %9.1f %9.1f %9.1f %8.1f %8.1f %8.1f %7zu %9.1f\n", vessels,
              parts, discovery_s, seen.size(), 100.0 * (u1.cpu_s - u0.cpu_s) / wall, u1.rss_mb,
              u1.hwm_mb, 1e3 * pct(latency, 50), 1e3 * pct(latency, 99), 1e3 * pct(latency, 100),
              latency.size(), 100.0 * (e1.cpu_s - e0.cpu_s) / wall);
  std::fflush(stdout);
  (void)lines;
  return 0;
}

/// Part 4: the shore at fleet scale, through a discovery server.
int run_shore(const Driver& d) {
  std::printf(
      "\n4. Shore at fleet scale: usv-fdi monitor --json --status and usv-fdi emulate, both "
      "clients of a\n   discovery server on 127.0.0.1 (docker/fleet_participants.xml); %g s "
      "measured once every vessel is shown\n",
      d.o.shore_seconds);
  std::printf("   %10s %9s %7s %9s %9s %9s %8s %8s %8s %7s %9s\n", "vessels/DP", "shown [s]",
              "shown", "mon CPU%", "RSS [MB]", "HWM [MB]", "ev p50", "ev p99", "ev max", "events",
              "emu CPU%");
  std::printf("   %10s %9s %7s %9s %9s %9s %8s %8s %8s %7s %9s\n", "", "", "", "", "", "", "[ms]",
              "[ms]", "[ms]", "", "");
  int port = 12811 + static_cast<int>(::getpid() % 1000);
  for (std::size_t i = 0; i < d.o.shore_vessels.size(); ++i) {
    if (run_shore_one(d, d.o.shore_vessels[i], d.o.shore_participants[i], port++) != 0) return 1;
  }
  std::printf(
      "   targets at 1000 vessels: monitor < 100 %% of a core and < 200 MB, event p99 < 50 ms, "
      "every vessel shown within 10 s\n");
  return 0;
}

/// Part 5 for one fleet size and filter setting: the sidecars' summed CPU [s] over the window.
struct FanoutRun {
  double cpu_per_sidecar = 0.0;  ///< [% of a core]
  double fleet_total = 0.0;      ///< [% of a core]
  double sim_cpu = 0.0;          ///< [% of a core]
};

bool run_fanout_one(const Driver& d, int n, bool filter, int port, FanoutRun* out) {
  const Options& o = d.o;
  const std::string tag = "fanout" + std::to_string(n) + (filter ? "f" : "n");
  FleetDiscovery fleet(d, tag, port, "bench_fanout_" + d.tag);
  const std::vector<std::string> dds_args = fleet.args();
  auto with_dds = [&dds_args](std::vector<std::string> head) {
    head.insert(head.end(), dds_args.begin(), dds_args.end());
    return head;
  };
  std::vector<std::unique_ptr<Child>> sidecars;
  std::vector<std::string> sim = {USV_FDI_EXE,
                                  "sim",
                                  "--publish",
                                  "--vessel",
                                  "otter",
                                  "--scenario",
                                  "healthy",
                                  "--rate",
                                  "10",
                                  "--duration",
                                  std::to_string(o.fanout_seconds + 10.0),
                                  "--min-readers",
                                  std::to_string(n),
                                  "--wait-readers",
                                  "60"};
  for (int i = 0; i < n; ++i) {
    const std::uint32_t mmsi = kMmsi + 100 + static_cast<std::uint32_t>(i);
    const std::string name = tag + "_" + std::to_string(i);
    const std::string cfg =
        write_service_config(d.dir, name, false, mmsi,
                             std::string("  content_filter: ") + (filter ? "true" : "false") +
                                 "\n  input_timeout: 60\n");
    sidecars.push_back(std::make_unique<Child>(with_dds({USV_FDI_EXE, "run", "--config", cfg}),
                                               d.dir + "/" + name + ".log"));
    sim.push_back("--mmsi");
    sim.push_back(std::to_string(mmsi));
  }
  for (int i = 0; i < n; ++i) {
    if (!wait_for_text(d.dir + "/" + tag + "_" + std::to_string(i) + ".log", "waiting for INS",
                       30)) {
      std::fprintf(stderr, "sidecar %d did not start; see %s\n", i, d.dir.c_str());
      return false;
    }
  }
  Child publisher(with_dds(sim), d.dir + "/" + tag + "_sim.log");
  // Measured once the simulator publishes (every sidecar's readers matched) and 5 s on.
  if (!wait_for_text(d.dir + "/" + tag + "_sim.log", "publishing", 60)) {
    std::fprintf(stderr, "the simulator did not start publishing; see %s\n", d.dir.c_str());
    return false;
  }
  std::this_thread::sleep_for(std::chrono::seconds(5));
  std::vector<ProcUsage> u0;
  for (const auto& c : sidecars) u0.push_back(usage(c->pid()));
  const ProcUsage p0 = usage(publisher.pid());
  const auto t0 = Clock::now();
  std::this_thread::sleep_for(std::chrono::duration<double>(o.fanout_seconds));
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  double total = 0.0;
  for (std::size_t i = 0; i < sidecars.size(); ++i) {
    total += usage(sidecars[i]->pid()).cpu_s - u0[i].cpu_s;
  }
  out->fleet_total = 100.0 * total / wall;
  out->cpu_per_sidecar = out->fleet_total / n;
  out->sim_cpu = 100.0 * (usage(publisher.pid()).cpu_s - p0.cpu_s) / wall;
  return true;
}

/// Part 5: per-sidecar CPU against fleet size, without and with the content filter.
int run_fanout(const Driver& d) {
  std::printf(
      "\n5. Input fan-out: N sidecars and one sim --publish of N vessels at 10 Hz on one "
      "partition,\n   clients of a discovery server on 127.0.0.1; CPU over %g s once the "
      "voyage is published\n",
      d.o.fanout_seconds);
  std::printf("   %8s %22s %22s %18s\n", "", "content_filter: false", "content_filter: true",
              "sim --publish [%]");
  std::printf("   %8s %11s %10s %11s %10s %9s %8s\n", "sidecars", "per sidecar", "fleet",
              "per sidecar", "fleet", "false", "true");
  int port = 13811 + static_cast<int>(::getpid() % 1000);
  for (int n : d.o.fanout_sidecars) {
    FanoutRun off, on;
    if (!run_fanout_one(d, n, false, port++, &off) || !run_fanout_one(d, n, true, port++, &on)) {
      return 1;
    }
    std::printf("   %8d %10.2f%% %9.1f%% %10.2f%% %9.1f%% %9.1f %8.1f\n", n, off.cpu_per_sidecar,
                off.fleet_total, on.cpu_per_sidecar, on.fleet_total, off.sim_cpu, on.sim_cpu);
    std::fflush(stdout);
  }
  return 0;
}

int run_driver(const Options& o, const char* self) {
  char tmpl[] = "/tmp/usv_fdi_bench_dds_XXXXXX";
  if (mkdtemp(tmpl) == nullptr) throw std::runtime_error("mkdtemp failed");
  const Driver d{o, self, tmpl, std::to_string(::getpid())};
  std::printf("usv-fdi DDS benchmark: domain %s, participant profile %s, logs in %s\n",
              std::to_string(o.domain).c_str(), o.participant.c_str(), d.dir.c_str());
  std::fflush(stdout);
  if (o.latency && run_latency(d) != 0) return 1;
  if (o.cpu && run_cpu(d) != 0) return 1;
  if (o.late_join && run_late_join(d) != 0) return 1;
  if (o.shore && run_shore(d) != 0) return 1;
  if (o.fanout && run_fanout(d) != 0) return 1;
  return 0;
}

/// What this process is: the driver, or one of the responders it starts.
enum class Role { kDriver, kEcho, kLatched };

Options parse(int argc, char** argv, Role* role) {
  Options o;
  const std::string first = argc > 1 ? argv[1] : "";
  *role = first == "echo" ? Role::kEcho : first == "latched" ? Role::kLatched : Role::kDriver;
  for (int i = *role == Role::kDriver ? 1 : 2; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--faults") {
      o.faults = std::stoi(value());
    } else if (a == "--block") {
      o.block = std::stoi(value());
    } else if (a == "--cpu-seconds") {
      o.cpu_seconds = std::stod(value());
    } else if (a == "--rate") {
      o.rate = std::stod(value());
    } else if (a == "--domain") {
      o.domain = static_cast<std::uint32_t>(std::stoul(value()));
    } else if (a == "--participant-profile") {
      o.participant = value();
    } else if (a == "--partition") {
      o.partition = value();
    } else if (a == "--skip-latency") {
      o.latency = false;
    } else if (a == "--skip-cpu") {
      o.cpu = false;
    } else if (a == "--skip-fanout") {
      o.fanout = false;
    } else if (a == "--fanout-seconds") {
      o.fanout_seconds = std::stod(value());
    } else if (a == "--fanout") {
      o.fanout_sidecars.clear();
      std::stringstream list(value());
      for (std::string n; std::getline(list, n, ',');) o.fanout_sidecars.push_back(std::stoi(n));
    } else if (a == "--skip-shore") {
      o.shore = false;
    } else if (a == "--shore-seconds") {
      o.shore_seconds = std::stod(value());
    } else if (a == "--shore-vessels") {
      o.shore_vessels.clear();
      o.shore_participants.clear();
      std::stringstream list(value());
      for (std::string n; std::getline(list, n, ',');) {
        const auto slash = n.find('/');
        o.shore_vessels.push_back(std::stoi(n.substr(0, slash)));
        o.shore_participants.push_back(slash == std::string::npos ? 0
                                                                  : std::stoi(n.substr(slash + 1)));
      }
    } else if (a == "--skip-late-join") {
      o.late_join = false;
    } else if (a == "--joins") {
      o.joins = std::stoi(value());
    } else if (a == "--profiles") {
      o.profiles = value();
    } else if (a == "--heartbeat-ms") {
      o.heartbeat_ms = std::stoi(value());
    } else {
      throw std::invalid_argument("unknown option " + a);
    }
  }
  if (o.faults < 1 || o.block < 1 || !(o.cpu_seconds > 0) || !(o.rate > 0) || o.domain > 232 ||
      o.joins < 1 || o.heartbeat_ms < 0) {
    throw std::invalid_argument(
        "--faults, --block, --cpu-seconds, --rate, --joins must be positive, --heartbeat-ms "
        "not negative, --domain 0..232");
  }
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    Role role = Role::kDriver;
    const Options o = parse(argc, argv, &role);
    if (role == Role::kEcho) return run_echo(o);
    if (role == Role::kLatched) return run_latched(o);
    char self[4096];
    const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0) throw std::runtime_error("readlink /proc/self/exe failed");
    self[n] = '\0';
    return run_driver(o, self);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "usv_fdi_bench_dds: %s\n", e.what());
    return 1;
  }
}
