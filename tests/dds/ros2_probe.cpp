// usv_fdi_ros2_probe: a ROS 2 node as seen on the wire, without ROS, for the tests of
// `usv-fdi ros2`. Topic /name is DDS topic rt/name, types are the ROS 2 types generated with
// `fastddsgen -typeros2` (sensor_msgs::msg::dds_::Imu_, ...), no partition, QoS as rclcpp's
// default profile (RELIABLE, VOLATILE, KEEP_LAST 10).
//
//   usv_fdi_ros2_probe publish-paper --profiles FILE --domain N --participant-profile P
//       [--speed S] [--rudder-sign K] [--imu /imu/data] [--twist /velocity]
//       [--rudder /rudder_angle] [--odometry /odom] [--qos default|sensor_data]
//       [--timeout SECONDS] [--lead-in SECONDS] [--burst N]
//     The paper's scenario (Otter, 50 Hz, noise-free; gyro bias on [20, 40) s, accelerometer
//     bias on [60, 80) s; --lead-in L: L s of healthy voyage before it, the faults L s later,
//     so that samples lost before the first fault leave the engine time to arm) from the
//     simulator, S times faster than real time (default 10), in
//     REP 103 signs: per sample std_msgs/Float64 rudder (K * δ, default K = 1), then
//     sensor_msgs/Imu (angular_velocity.z = -r), then geometry_msgs/TwistStamped
//     (twist.linear.y = -v), stamps t; with --odometry, nav_msgs/Odometry on that topic
//     (twist.twist.linear.y = -v) instead of the TwistStamped. --surge /topic: also a
//     geometry_msgs/TwistStamped per sample on that topic, linear.x = kSurgeOwnTopic (1.5 m/s; the
//     sway message's linear.x is 1). --qos sensor_data: writers as
//     rclcpp's sensor_data profile (BEST_EFFORT, KEEP_LAST 5). --burst N: the samples go out N at
//     a time, as a reader sees them when its delivery thread falls behind: the Imu and twist
//     samples of N instants first, then their N rudder angles, each with the DDS source
//     timestamp of the instant it stands for (a rudder angle just before its Imu sample).
//     Waits (up to the timeout, default 20 s) until a reader matches each writer, prints
//     "publishing", then "published N" and exits 0.
//
//   usv_fdi_ros2_probe read-diagnostics --profiles FILE --domain N --participant-profile P
//     Reads /diagnostics (diagnostic_msgs/DiagnosticArray) and the transient-local mirror
//     /usv_fdi/fault_event (usv_fdi_msgs/FaultEvent). Prints, per DiagnosticStatus,
//       diag level=L hardware_id=H name=<name> | key=value key=value ...
//     and per mirror sample
//       mirror mmsi=M sensor=S state=T sequence=Q kind=K c_a=X c_g=Y
//     and per sample of the transient-local mirror /usv_fdi/status (usv_fdi_msgs/FdiStatus)
//       status mmsi=M stamp=T armed=0|1 samples=N surge=U
//     until SIGTERM/SIGINT (exit 0).
//
// Exit code 3: usage error; 4: DDS error.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include "diagnostic_msgsPubSubTypes.h"
#include "geometry_msgsPubSubTypes.h"
#include "nav_msgsPubSubTypes.h"
#include "probe_common.hpp"
#include "sensor_msgsPubSubTypes.h"
#include "std_msgsPubSubTypes.h"
#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/dds/profiles.hpp"
#include "usv_fdi_msgsPubSubTypes.h"

namespace {

namespace fdds = eprosima::fastdds::dds;
namespace probe = usvfdi::test_support::probe;
using eprosima::fastrtps::types::ReturnCode_t;
using probe::UsageError;

struct DdsError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Options {
  std::string mode, profiles, participant_profile = "usv_fdi_participant_loopback";
  std::uint32_t domain = 0;
  double speed = 10.0, timeout = 20.0, lead_in = 0.0;
  int rudder_sign = 1;
  std::string imu = "rt/imu/data", twist = "rt/velocity", rudder = "rt/rudder_angle";
  std::string odometry;  ///< empty: TwistStamped on `twist`
  std::string surge;     ///< non-empty: a TwistStamped of its own with the surge speed
  bool sensor_data = false;
  unsigned burst = 1;
};

std::string rt(const std::string& ros) { return "rt/" + (ros[0] == '/' ? ros.substr(1) : ros); }

Options parse(int argc, char** argv) {
  if (argc < 2) throw UsageError("usage: usv_fdi_ros2_probe publish-paper|read-diagnostics ...");
  Options o;
  o.mode = argv[1];
  for (int i = 2; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) throw UsageError(flag + ": missing value");
    const std::string value = argv[++i];
    if (flag == "--profiles") {
      o.profiles = value;
    } else if (flag == "--domain") {
      o.domain = static_cast<std::uint32_t>(probe::parse_unsigned(flag, value));
    } else if (flag == "--participant-profile") {
      o.participant_profile = value;
    } else if (flag == "--speed") {
      o.speed = std::stod(value);
    } else if (flag == "--timeout") {
      o.timeout = std::stod(value);
    } else if (flag == "--lead-in") {
      o.lead_in = std::stod(value);
      if (!(o.lead_in >= 0.0)) throw UsageError("--lead-in: " + value + " (seconds, >= 0)");
    } else if (flag == "--rudder-sign") {
      o.rudder_sign = std::stoi(value);
    } else if (flag == "--imu") {
      o.imu = rt(value);
    } else if (flag == "--twist") {
      o.twist = rt(value);
    } else if (flag == "--rudder") {
      o.rudder = rt(value);
    } else if (flag == "--odometry") {
      o.odometry = rt(value);
    } else if (flag == "--surge") {
      o.surge = rt(value);
    } else if (flag == "--burst") {
      o.burst = static_cast<unsigned>(probe::parse_unsigned(flag, value));
      if (o.burst < 1) throw UsageError("--burst: " + value + " (>= 1)");
    } else if (flag == "--qos") {
      if (value != "default" && value != "sensor_data") throw UsageError("--qos: " + value);
      o.sensor_data = value == "sensor_data";
    } else {
      throw UsageError("unknown option " + flag);
    }
  }
  if (o.profiles.empty()) throw UsageError("--profiles is required");
  return o;
}

/// A participant with ROS 2 topics; everything deleted with it.
class Node {
 public:
  explicit Node(const Options& o) {
    usvfdi::dds::load_profiles_file(o.profiles);
    auto* f = fdds::DomainParticipantFactory::get_instance();
    p_ = f->create_participant_with_profile(o.domain, o.participant_profile);
    if (p_ == nullptr) throw DdsError("cannot create the participant");
    pub_ = p_->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
    sub_ = p_->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
    if (pub_ == nullptr || sub_ == nullptr) throw DdsError("cannot create publisher/subscriber");
  }
  ~Node() {
    p_->delete_contained_entities();
    fdds::DomainParticipantFactory::get_instance()->delete_participant(p_);
  }
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  fdds::Topic* topic(const std::string& name, fdds::TypeSupport type) {
    if (type.register_type(p_) != ReturnCode_t::RETCODE_OK) throw DdsError("register_type");
    fdds::Topic* t = p_->create_topic(name, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    if (t == nullptr) throw DdsError("cannot create topic " + name);
    return t;
  }
  /// rclcpp's default publisher QoS: RELIABLE, VOLATILE, KEEP_LAST 10; sensor_data:
  /// BEST_EFFORT, VOLATILE, KEEP_LAST 5.
  fdds::DataWriter* writer(fdds::Topic* t, bool sensor_data = false) {
    fdds::DataWriterQos q = fdds::DATAWRITER_QOS_DEFAULT;
    q.reliability().kind =
        sensor_data ? fdds::BEST_EFFORT_RELIABILITY_QOS : fdds::RELIABLE_RELIABILITY_QOS;
    q.durability().kind = fdds::VOLATILE_DURABILITY_QOS;
    q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
    q.history().depth = sensor_data ? 5 : 10;
    fdds::DataWriter* w = pub_->create_datawriter(t, q);
    if (w == nullptr) throw DdsError("cannot create a writer of " + t->get_name());
    return w;
  }
  fdds::DataReader* reader(fdds::Topic* t, bool transient_local) {
    fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
    q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
    q.durability().kind =
        transient_local ? fdds::TRANSIENT_LOCAL_DURABILITY_QOS : fdds::VOLATILE_DURABILITY_QOS;
    q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
    q.history().depth = 100;
    fdds::DataReader* r = sub_->create_datareader(t, q);
    if (r == nullptr) throw DdsError("cannot create a reader of " + t->get_name());
    return r;
  }

 private:
  fdds::DomainParticipant* p_ = nullptr;
  fdds::Publisher* pub_ = nullptr;
  fdds::Subscriber* sub_ = nullptr;
};

void set_stamp(std_msgs::msg::Header* h, double t) {
  const double whole = std::floor(t);
  h->stamp().sec(static_cast<std::int32_t>(whole));
  h->stamp().nanosec(static_cast<std::uint32_t>(std::llround((t - whole) * 1e9)) % 1000000000u);
}

/// The surge speed --surge publishes [m/s]: not the sway message's linear.x (1), so that a reader
/// can tell which topic it came from.
constexpr double kSurgeOwnTopic = 1.5;

int publish_paper(const Options& o) {
  Node n(o);
  const bool be = o.sensor_data;
  fdds::DataWriter* surge_w =
      o.surge.empty()
          ? nullptr
          : n.writer(n.topic(o.surge,
                             fdds::TypeSupport(new geometry_msgs::msg::TwistStampedPubSubType())),
                     be);
  fdds::DataWriter* rudder_w =
      n.writer(n.topic(o.rudder, fdds::TypeSupport(new std_msgs::msg::Float64PubSubType())), be);
  fdds::DataWriter* imu_w =
      n.writer(n.topic(o.imu, fdds::TypeSupport(new sensor_msgs::msg::ImuPubSubType())), be);
  fdds::DataWriter* twist_w =
      o.odometry.empty()
          ? n.writer(n.topic(o.twist,
                             fdds::TypeSupport(new geometry_msgs::msg::TwistStampedPubSubType())),
                     be)
          : n.writer(
                n.topic(o.odometry, fdds::TypeSupport(new nav_msgs::msg::OdometryPubSubType())),
                be);
  const auto deadline = probe::deadline_after(o.timeout);
  for (;;) {
    fdds::PublicationMatchedStatus a, b, c;
    rudder_w->get_publication_matched_status(a);
    imu_w->get_publication_matched_status(b);
    twist_w->get_publication_matched_status(c);
    fdds::PublicationMatchedStatus d;
    d.current_count = 1;
    if (surge_w != nullptr) surge_w->get_publication_matched_status(d);
    if (a.current_count > 0 && b.current_count > 0 && c.current_count > 0 && d.current_count > 0)
      break;
    if (probe::Clock::now() >= deadline || probe::g_stop.load()) {
      std::printf("no reader matched\n");
      return 2;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  // The readers (BEST_EFFORT) match only after their side has discovered us too: a moment.
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  std::printf("publishing\n");
  std::fflush(stdout);

  usvfdi::SimConfig cfg = usvfdi::paper_scenario(usvfdi::otter(), 50.0, 1);
  cfg.sigma_v = 0.0;  // noise-free, as `usv-fdi sim --noise-scale 0`
  cfg.sigma_r = 0.0;
  cfg.duration += o.lead_in;
  for (usvfdi::FaultInjection& f : cfg.faults) {
    f.t_start += o.lead_in;
    f.t_end += o.lead_in;
  }
  usvfdi::Simulator sim(cfg);
  usvfdi::SimRow row;
  auto t0 = probe::Clock::now();
  std::uint64_t n_pub = 0;
  // One instant's messages, and its DDS source timestamp (system clock) with --burst.
  struct Instant {
    std_msgs::msg::Float64 rudder;
    sensor_msgs::msg::Imu imu;
    geometry_msgs::msg::TwistStamped twist;
    nav_msgs::msg::Odometry odom;
    geometry_msgs::msg::TwistStamped surge;
    double sent = 0.0;
  };
  std::vector<Instant> burst;
  const auto write_at = [](fdds::DataWriter* w, void* data, double sent) {
    if (sent > 0.0) {
      w->write_w_timestamp(data, fdds::HANDLE_NIL, eprosima::fastrtps::Time_t(sent));
    } else {
      w->write(data);
    }
  };
  const auto write_sway = [&](Instant& x, double sent) {
    if (o.odometry.empty()) {
      write_at(twist_w, &x.twist, sent);
    } else {
      write_at(twist_w, &x.odom, sent);
    }
    if (surge_w != nullptr) write_at(surge_w, &x.surge, sent);
  };
  const auto write_burst = [&] {
    if (burst.empty()) return;
    if (o.burst == 1) {
      write_at(rudder_w, &burst[0].rudder, 0.0);
      write_at(imu_w, &burst[0].imu, 0.0);
      write_sway(burst[0], 0.0);
    } else {
      // The instants' source times, 1/rate apart (wall time) up to now; each rudder angle
      // 1 ms before its Imu sample.
      const double wall_now =
          std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
              .count();
      const double step = 1.0 / (50.0 * o.speed);
      for (std::size_t j = 0; j < burst.size(); ++j) {
        burst[j].sent = wall_now - static_cast<double>(burst.size() - 1 - j) * step;
      }
      for (Instant& b : burst) {
        write_at(imu_w, &b.imu, b.sent + 1e-3);
        write_sway(b, b.sent + 1e-3);
      }
      for (Instant& b : burst) write_at(rudder_w, &b.rudder, b.sent);
    }
    burst.clear();
  };
  while (!probe::g_stop.load() && sim.next(&row)) {
    const auto due = t0 + std::chrono::duration_cast<probe::Clock::duration>(
                              std::chrono::duration<double>(row.t / o.speed));
    Instant x;
    x.rudder.data(o.rudder_sign * row.delta);
    set_stamp(&x.imu.header(), row.t);
    x.imu.header().frame_id("imu_link");
    x.imu.orientation().w(1.0);
    x.imu.orientation_covariance()[0] = -1.0;  // no orientation estimate
    x.imu.angular_velocity().z(-row.r);        // REP 103: z up
    set_stamp(&x.twist.header(), row.t);
    x.twist.header().frame_id("base_link");
    x.twist.twist().linear().x(1.0);
    x.twist.twist().linear().y(-row.v);  // REP 103: y to port
    x.twist.twist().angular().z(-row.r);
    x.surge.header(x.twist.header());
    x.surge.twist().linear().x(kSurgeOwnTopic);
    if (!o.odometry.empty()) {
      x.odom.header(x.twist.header());
      x.odom.header().frame_id("odom");
      x.odom.child_frame_id("base_link");
      x.odom.pose().pose().orientation().w(1.0);
      x.odom.twist().twist(x.twist.twist());
    }
    burst.push_back(x);
    ++n_pub;
    if (burst.size() < o.burst) continue;
    const auto now = probe::Clock::now();
    if (now > due + std::chrono::milliseconds(250)) {
      t0 += now - due;  // behind (a busy machine): shift the schedule, no burst
    } else {
      std::this_thread::sleep_until(due);
    }
    write_burst();
  }
  write_burst();  // the last instants, fewer than --burst
  rudder_w->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(2.0));
  std::printf("published %llu\n", static_cast<unsigned long long>(n_pub));
  std::fflush(stdout);
  return 0;
}

int read_diagnostics(const Options& o) {
  Node n(o);
  fdds::DataReader* diag =
      n.reader(n.topic("rt/diagnostics",
                       fdds::TypeSupport(new diagnostic_msgs::msg::DiagnosticArrayPubSubType())),
               false);
  fdds::DataReader* mirror =
      n.reader(n.topic("rt/usv_fdi/fault_event",
                       fdds::TypeSupport(new usv_fdi_msgs::msg::FaultEventPubSubType())),
               true);
  fdds::DataReader* status = n.reader(
      n.topic("rt/usv_fdi/status", fdds::TypeSupport(new usv_fdi_msgs::msg::FdiStatusPubSubType())),
      true);
  fdds::WaitSet ws;
  for (fdds::DataReader* r : {diag, mirror, status}) {
    r->get_statuscondition().set_enabled_statuses(fdds::StatusMask::data_available());
    ws.attach_condition(r->get_statuscondition());
  }
  std::printf("reading\n");
  std::fflush(stdout);
  while (!probe::g_stop.load()) {
    fdds::ConditionSeq active;
    ws.wait(active, eprosima::fastrtps::Duration_t(0.1));
    fdds::SampleInfo info;
    diagnostic_msgs::msg::DiagnosticArray a;
    while (diag->take_next_sample(&a, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      for (const auto& s : a.status()) {
        std::string line = "diag level=" + std::to_string(s.level()) +
                           " hardware_id=" + s.hardware_id() + " name=" + s.name() + " |";
        for (const auto& kv : s.values()) line += " " + kv.key() + "=" + kv.value();
        std::printf("%s\n", line.c_str());
      }
    }
    usv_fdi_msgs::msg::FaultEvent e;
    while (mirror->take_next_sample(&e, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      std::printf("mirror mmsi=%u sensor=%u state=%u sequence=%llu kind=%u c_a=%.3f c_g=%.3f\n",
                  e.mmsi(), static_cast<unsigned>(e.sensor()), static_cast<unsigned>(e.state()),
                  static_cast<unsigned long long>(e.sequence_number()),
                  static_cast<unsigned>(e.kind()), e.c_a(), e.c_g());
    }
    usv_fdi_msgs::msg::FdiStatus st;
    while (status->take_next_sample(&st, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      std::printf("status mmsi=%u stamp=%.1f armed=%d samples=%llu surge=%.3f\n", st.mmsi(),
                  st.stamp(), st.armed() ? 1 : 0, static_cast<unsigned long long>(st.samples()),
                  st.surge_speed());
    }
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  probe::install_signal_handlers();
  try {
    const Options o = parse(argc, argv);
    if (o.mode == "publish-paper") return publish_paper(o);
    if (o.mode == "read-diagnostics") return read_diagnostics(o);
    throw UsageError("unknown mode " + o.mode);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "DDS error: %s\n", e.what());
    return 4;
  }
}
