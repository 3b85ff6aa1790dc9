#include "service_fleet.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace usvfdi::fleet::test {
namespace {

namespace fs = std::filesystem;
using dds::test::ChildProcess;
using Clock = std::chrono::steady_clock;

constexpr const char* kExe = USV_FDI_EXE;
const std::string kSource = USV_FDI_SOURCE_DIR;

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream os;
  os << f.rdbuf();
  return os.str();
}

/// The discovery server binary (`fastdds discovery` is a Python wrapper that runs it as a child,
/// which a SIGKILL of the wrapper would leave behind).
std::string discovery_server_exe() {
  for (const char* p : {"/usr/bin/fast-discovery-server", "/usr/local/bin/fast-discovery-server"}) {
    if (::access(p, X_OK) == 0) return p;
  }
  throw std::runtime_error("fast-discovery-server not found (fastdds-tools, scripts/packages.txt)");
}

}  // namespace

ServiceFleet::ServiceFleet(Options o)
    : opt_(std::move(o)), net_(opt_.name, opt_.vessels), t0_(Clock::now()) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string test = std::string(info->test_suite_name()) + "_" + info->name();
  for (char& c : test) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  dir_ = ::testing::TempDir() + "usv_fdi_" + test + "_" + std::to_string(::getpid()) + "/";
  fs::create_directories(dir_);
  if (!opt_.secure_pki.empty()) {
    // As in docker/compose.secure.yaml.
    env_ = {"FASTRTPS_DEFAULT_PROFILES_FILE=" + opt_.secure_pki + "/security_profiles.xml"};
    return;
  }
  if (opt_.participant_profiles.empty()) {
    opt_.participant_profiles = kSource + "/docker/fleet_participants.xml";
  }
  env_ = {"FASTRTPS_DEFAULT_PROFILES_FILE=" + opt_.participant_profiles,
          // As in docker/compose.yaml: every participant is a client of both servers.
          "ROS_DISCOVERY_SERVER=10.77.0.2:11811;10.77.0.3:11811"};
}

ServiceFleet::~ServiceFleet() {
  procs_.clear();  // SIGKILL + reap; the namespaces (and what else runs there) go with net_
  if (!::testing::Test::HasFailure()) {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  } else {
    std::fprintf(stderr, "logs kept in %s\n", dir_.c_str());
  }
}

double ServiceFleet::now() const {
  return std::chrono::duration<double>(Clock::now() - t0_).count();
}

std::vector<std::string> ServiceFleet::vessel_dds(unsigned i, bool sim) const {
  const std::string profile =
      opt_.secure_pki.empty()
          ? opt_.vessel_profile
          : "usv_fdi_secure_vessel" + std::to_string(i) + (sim ? "-sim" : "") + "_unicast";
  return {"--qos",
          kSource + "/config/qos/usv_fdi_profiles.xml",
          "--participant-profile",
          profile,
          "--partition",
          partition(i)};
}

std::vector<std::string> ServiceFleet::shore_dds() const {
  const std::string profile =
      opt_.secure_pki.empty() ? opt_.shore_profile : "usv_fdi_secure_shore_unicast";
  return {"--qos",
          kSource + "/config/qos/usv_fdi_profiles.xml",
          "--participant-profile",
          profile,
          "--partition",
          "vessel-*"};
}

ChildProcess& ServiceFleet::start(const std::string& node, const std::string& name,
                                  const std::vector<std::string>& argv, bool fleet_env) {
  if (procs_.count(name) != 0) throw std::logic_error("process name used twice: " + name);
  auto p = std::make_unique<ChildProcess>(net_.in(node, argv), dir_ + name + ".log",
                                          fleet_env ? env_ : std::vector<std::string>{});
  ChildProcess& ref = *p;
  procs_[name] = std::move(p);
  return ref;
}

bool ServiceFleet::start_discovery_servers() {
  const std::string exe = discovery_server_exe();
  const std::string profile =
      "usv_fdi_discovery_server_udp@" + kSource + "/docker/fleet_participants.xml";
  for (int id : {0, 1}) {
    const std::string node = "d" + std::to_string(id);
    // Not the clients' environment (as in the compose file): given ROS_DISCOVERY_SERVER, the
    // 2.9 server also takes the listed addresses for remote servers and aborts (an assertion in
    // OutputTrafficManager::set_statistics_message_data).
    start(node, "discovery" + std::to_string(id),
          {exe, "-i", std::to_string(id), "-l", net_.addr(node), "-p", "11811", "-x", profile},
          false);
  }
  // Bounded wait until both listen (clients would also find a late server: they keep pinging).
  const auto deadline = Clock::now() + std::chrono::seconds(10);
  for (const std::string node : {"d0", "d1"}) {
    for (;;) {
      ChildProcess ss(net_.in(node, {"/usr/bin/ss", "-lun"}));
      const std::string out = ss.read_all(std::chrono::milliseconds(3000));
      ss.wait_exit(std::chrono::milliseconds(1000));
      if (out.find(":11811 ") != std::string::npos) break;
      if (Clock::now() >= deadline) {
        ADD_FAILURE() << "discovery server on " << node << " not listening after 10 s:\n" << out;
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
  return true;
}

ChildProcess& ServiceFleet::start_monitor(const std::string& name,
                                          const std::vector<std::string>& extra) {
  std::vector<std::string> argv = {kExe, "monitor", "--json", "--status"};
  const auto d = shore_dds();
  argv.insert(argv.end(), d.begin(), d.end());
  argv.insert(argv.end(), extra.begin(), extra.end());
  return start("shore", name, argv);
}

ChildProcess& ServiceFleet::start_sidecar(unsigned i, const std::vector<std::string>& extra_yaml) {
  const std::string name = "sidecar" + std::to_string(i);
  const std::string cfg = dir_ + name + ".yaml";
  {
    std::ofstream f(cfg);
    // The compose file runs config/scenarios/paper.yaml as it is; the test adds a faster status
    // (the test reads counters from it) and an input timeout that a loaded machine cannot trip.
    f << slurp(kSource + "/config/scenarios/paper.yaml");
    // A status at least every second (the partition test times the shore's silent verdict).
    f << "\nservice:\n  status_rate: 5\n  status_uplink: {heartbeat: 1}\n  input_timeout: 60\n"
      << "  rudder_wait: 1.0\n";
    for (const auto& line : extra_yaml) f << "  " << line << "\n";
    if (!f) throw std::runtime_error("cannot write " + cfg);
  }
  std::vector<std::string> argv = {
      kExe, "run", "--config", cfg, "--mmsi", std::to_string(mmsi(i)), "--reliable-inputs"};
  const auto d = vessel_dds(i);
  argv.insert(argv.end(), d.begin(), d.end());
  ChildProcess& p = start("v" + std::to_string(i), name, argv);
  EXPECT_TRUE(wait_for_log(name, "waiting for INS and rudder", std::chrono::seconds(15)))
      << log(name);
  return p;
}

ChildProcess& ServiceFleet::start_sim(unsigned i, const std::vector<std::string>& extra) {
  std::vector<std::string> argv = {kExe,
                                   "sim",
                                   "--publish",
                                   "--vessel",
                                   "otter",
                                   "--scenario",
                                   "paper",
                                   "--noise-scale",
                                   "0",
                                   "--reliable",
                                   "--linger",
                                   "0.5",
                                   "--wait-readers",
                                   "30",
                                   "--mmsi",
                                   std::to_string(mmsi(i))};
  argv.insert(argv.end(), extra.begin(), extra.end());
  const auto d = vessel_dds(i, true);
  argv.insert(argv.end(), d.begin(), d.end());
  return start("v" + std::to_string(i), "sim" + std::to_string(i), argv);
}

std::optional<int> ServiceFleet::run_on_shore(const std::string& name,
                                              std::vector<std::string> args,
                                              std::chrono::milliseconds timeout, std::string* out) {
  std::vector<std::string> argv = {kExe};
  argv.insert(argv.end(), args.begin(), args.end());
  const auto d = shore_dds();
  argv.insert(argv.end(), d.begin(), d.end());
  ChildProcess& p = start("shore", name, argv);
  const std::string text = p.read_all(timeout);
  if (out != nullptr) *out = text;
  return p.wait_exit(std::chrono::milliseconds(3000));
}

std::string ServiceFleet::log(const std::string& name) const { return slurp(dir_ + name + ".log"); }

bool ServiceFleet::wait_for_log(const std::string& name, const std::string& text,
                                std::chrono::milliseconds timeout) const {
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    if (log(name).find(text) != std::string::npos) return true;
    if (Clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

std::optional<int> ServiceFleet::stop(const std::string& name, std::chrono::milliseconds timeout) {
  ChildProcess& p = process(name);
  p.signal(SIGTERM);
  return p.wait_exit(timeout);
}

std::string ServiceFleet::logs_tail() const {
  std::string s;
  for (const auto& [name, p] : procs_) {
    const std::string text = log(name);
    std::size_t at = text.size();
    for (int lines = 0; lines < 12 && at > 0; ++lines) {
      const auto nl = text.rfind('\n', at - 1);
      at = nl == std::string::npos ? 0 : nl;
    }
    s += "--- " + name + ".log\n" + text.substr(at) + "\n";
  }
  return s;
}

}  // namespace usvfdi::fleet::test
