#include "fleet.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "io/json_lite.hpp"
#include "test_env.hpp"

namespace usvfdi::dds::test {
namespace {

namespace js = usvfdi::testing_json;
namespace fs = std::filesystem;

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream os;
  os << f.rdbuf();
  return os.str();
}

}  // namespace

bool parse_monitor_line(const std::string& line, std::vector<MonitorEvent>* events,
                        std::vector<MonitorStatus>* statuses, std::string* error,
                        std::vector<MonitorVessel>* vessels) {
  try {
    const test_support::MonitorLine l = test_support::parse_monitor_json(line);
    if (l.type == "fault" && events != nullptr) events->push_back(l.fault);
    if (l.type == "status" && statuses != nullptr) statuses->push_back(l.status);
    if (l.type == "vessel" && vessels != nullptr) vessels->push_back(l.vessel);
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
  return true;
}

std::vector<std::string> sim_args(const std::vector<std::string>& extra) {
  std::vector<std::string> a = {"sim",   "--publish",     "--vessel", "otter",      "--scenario",
                                "paper", "--noise-scale", "0",        "--reliable", "--linger",
                                "0.2"};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

Fleet::Fleet() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(info->test_suite_name()) + "_" + info->name();
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  dir_ = ::testing::TempDir() + "usv_fdi_" + name + "_" + std::to_string(::getpid()) + "/";
  fs::create_directories(dir_);
  domain_ = std::to_string(test_domain_id());
  partition_ = unique_partition();
}

Fleet::~Fleet() {
  procs_.clear();  // ChildProcess: SIGKILL + reap whatever still runs
  if (!::testing::Test::HasFailure()) {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  } else {
    std::fprintf(stderr, "logs kept in %s\n", dir_.c_str());
  }
}

std::vector<std::string> Fleet::dds_args() const {
  return {"--domain",
          domain_,
          "--partition",
          partition_,
          "--participant-profile",
          "usv_fdi_participant_loopback",
          "--qos",
          kProfilesFile};
}

std::string Fleet::write_service_config(const std::string& name, unsigned mmsi,
                                        const std::vector<std::string>& extra) const {
  const std::string path = dir_ + name + ".yaml";
  std::ofstream f(path);
  f << slurp(std::string(USV_FDI_SOURCE_DIR) + "/config/scenarios/paper.yaml");
  f << "\nservice:\n  mmsi: " << mmsi << "\n";
  // The defaults, unless a line of `extra` gives the key (the loader refuses a key given
  // twice). Each sidecar config gets a state directory of its own (never the host's default).
  const std::pair<std::string, std::string> defaults[] = {
      {"reliable_inputs", "true"},
      {"status_rate", "5"},
      {"state_dir", state_dir(name)},
      // The simulator publishes 20-25 times faster than real time: a rudder sample repaired
      // by a reliable resend (heartbeats every 100 ms) reaches a busy machine's sidecar some
      // 0.2 s of wall time, several seconds of source time, after its INS sample.
      {"rudder_wait", "1.0"}};
  for (const auto& [key, value] : defaults) {
    bool given = false;
    for (const auto& line : extra) given |= line.rfind(key + ":", 0) == 0;
    if (!given) f << "  " << key << ": " << value << "\n";
  }
  for (const auto& line : extra) f << "  " << line << "\n";
  if (!f) throw std::runtime_error("cannot write " + path);
  return path;
}

ChildProcess& Fleet::start(const std::string& name, std::vector<std::string> args,
                           const std::vector<std::string>& extra_env, bool dds) {
  std::vector<std::string> argv = {USV_FDI_EXE};
  argv.insert(argv.end(), args.begin(), args.end());
  if (dds) {
    const auto d = dds_args();
    argv.insert(argv.end(), d.begin(), d.end());
  }
  auto p = std::make_unique<ChildProcess>(argv, dir_ + name + ".log", extra_env);
  ChildProcess& ref = *p;
  procs_[name] = std::move(p);
  return ref;
}

ChildProcess& Fleet::start_probe(const std::string& name, const std::string& mode,
                                 std::vector<std::string> args) {
  std::vector<std::string> argv = {kProbe,
                                   mode,
                                   "--profiles",
                                   kProfilesFile,
                                   "--domain",
                                   domain_,
                                   "--partition",
                                   partition_,
                                   "--participant-profile",
                                   "usv_fdi_participant_loopback"};
  argv.insert(argv.end(), args.begin(), args.end());
  auto p = std::make_unique<ChildProcess>(argv, dir_ + name + ".log");
  ChildProcess& ref = *p;
  procs_[name] = std::move(p);
  return ref;
}

std::string Fleet::log(const std::string& name) const { return slurp(dir_ + name + ".log"); }

bool Fleet::wait_for_log(const std::string& name, const std::string& text,
                         std::chrono::milliseconds timeout) const {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    if (log(name).find(text) != std::string::npos) return true;
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

ChildProcess& Fleet::start_service(const std::string& name, const std::string& config,
                                   int wait_monitors, std::vector<std::string> extra_args) {
  std::vector<std::string> args = {"run", "--config", config};
  args.insert(args.end(), extra_args.begin(), extra_args.end());
  ChildProcess& p = start(name, args);
  EXPECT_TRUE(wait_for_log(name, "waiting for INS and rudder", std::chrono::seconds(10)))
      << log(name);
  if (wait_monitors > 0) {
    const std::string text = std::to_string(wait_monitors) + " fault-event reader(s)";
    EXPECT_TRUE(wait_for_log(name, text, std::chrono::seconds(15))) << log(name);
  }
  return p;
}

std::optional<int> Fleet::run_to_end(const std::string& name, std::vector<std::string> args,
                                     std::chrono::milliseconds timeout, std::string* out,
                                     bool dds) {
  ChildProcess& p = start(name, std::move(args), {}, dds);
  const std::string text = p.read_all(timeout);
  if (out != nullptr) *out = text;
  return p.wait_exit(std::chrono::milliseconds(2000));
}

}  // namespace usvfdi::dds::test
