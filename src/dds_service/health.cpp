#include "usv_fdi/dds_service/health.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "usv_fdi/io/jsonl.hpp"

namespace usvfdi::dds_service {
namespace {

std::string num(double x) {
  if (!std::isfinite(x)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", x);
  return buf;
}

std::string fixed(const char* format, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

}  // namespace

void judge_threads(HealthReport* r) {
  std::string why;
  const auto check = [&](const char* name, double age) {
    if (age <= r->stall_limit) return;
    if (!why.empty()) why += "; ";
    why += std::string(name) + " thread stalled: it has not advanced for " + fixed("%.1f s", age) +
           " (limit " + fixed("%g s", r->stall_limit) + ")";
  };
  check("isolation", r->live.isolation);
  check("identification", r->live.identification);
  check("publisher", r->live.publisher);
  if (!why.empty()) {
    r->state = "failed";
    r->reason = why;
  }
}

std::string health_json(const HealthReport& r) {
  std::ostringstream os;
  os << "{\"version\": 1, \"time\": " << fixed("%.3f", r.time) << ", \"pid\": " << r.pid
     << ", \"mmsi\": " << r.mmsi << ", \"state\": " << io::json_string(r.state)
     << ", \"reason\": " << io::json_string(r.reason) << ", \"period\": " << num(r.period)
     << ", \"stall_limit\": " << num(r.stall_limit)
     << ", \"isolation_thread_age\": " << num(r.live.isolation)
     << ", \"ident_thread_age\": " << num(r.live.identification)
     << ", \"publisher_thread_age\": " << num(r.live.publisher)
     << ", \"ins_age\": " << (r.live.ins_age < 0 ? "null" : num(r.live.ins_age))
     << ", \"rudder_age\": " << (r.live.rudder_age < 0 ? "null" : num(r.live.rudder_age))
     << ", \"samples\": " << r.samples << ", \"converged\": " << (r.converged ? "true" : "false")
     << ", \"armed\": " << (r.armed ? "true" : "false") << ", \"input_flags\": "
     << io::json_string_array(pipeline::input_flag_names(r.input_flags), ", ")
     << ", \"identification_paused\": "
     << io::json_string_array(pipeline::pause_reason_names(r.identification_paused), ", ")
     << ", \"isolation_paused\": "
     << io::json_string_array(pipeline::pause_reason_names(r.isolation_paused), ", ")
     << ", \"dropped\": " << r.dropped << ", \"fault_event_readers\": " << r.fault_event_readers
     << ", \"state_file\": " << io::json_string(r.state_file)
     << ", \"state_error\": " << io::json_string(r.state_error) << "}\n";
  return os.str();
}

bool write_health_file(const std::string& path, const HealthReport& r, std::string* error) {
  const std::string tmp = path + ".tmp";
  const std::string text = health_json(r);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    *error = "cannot create " + tmp + ": " + std::strerror(errno);
    return false;
  }
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      *error = "cannot write " + tmp + ": " + std::strerror(errno);
      ::close(fd);
      ::unlink(tmp.c_str());
      return false;
    }
    done += static_cast<std::size_t>(n);
  }
  ::close(fd);
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    *error = "cannot rename " + tmp + " to " + path + ": " + std::strerror(errno);
    ::unlink(tmp.c_str());
    return false;
  }
  return true;
}

HealthVerdict check_health_file(const std::string& path, double max_age, double now_unix) {
  HealthVerdict v;
  const auto bad = [&](const std::string& why) {
    v.healthy = false;
    v.line = "unhealthy: " + why;
    return v;
  };
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) {
      return bad("no health file " + path + " (is `usv-fdi run --health-file " + path +
                 "` running?)");
    }
    return bad("cannot read " + path + ": " + std::strerror(errno));
  }
  if (S_ISDIR(st.st_mode)) return bad("cannot read " + path + ": " + std::strerror(EISDIR));
  std::ifstream f(path);
  if (!f) return bad("cannot read " + path + ": " + std::strerror(errno));
  std::stringstream ss;
  ss << f.rdbuf();
  YAML::Node root;
  try {
    root = YAML::Load(ss.str());
  } catch (const YAML::Exception& e) {
    return bad(path + " is not a health file (" + e.what() + ")");
  }
  double time = 0, period = 1;
  std::string state, reason;
  double threads[3] = {0, 0, 0};
  const char* thread_names[3] = {"isolation", "identification", "publisher"};
  const char* thread_keys[3] = {"isolation_thread_age", "ident_thread_age", "publisher_thread_age"};
  std::uint64_t samples = 0;
  std::string flags;
  try {
    if (!root.IsMap() || !root["version"] || root["version"].as<int>() != 1) {
      return bad(path + " is not a version-1 health file");
    }
    time = root["time"].as<double>();
    period = root["period"].as<double>();
    state = root["state"].as<std::string>();
    reason = root["reason"].as<std::string>();
    for (int i = 0; i < 3; ++i) threads[i] = root[thread_keys[i]].as<double>();
    samples = root["samples"].as<std::uint64_t>();
    for (const auto& n : root["input_flags"]) {
      flags += (flags.empty() ? "" : ",") + n.as<std::string>();
    }
  } catch (const YAML::Exception& e) {
    return bad(path + ": a field is missing or has the wrong type (" + e.what() + ")");
  }
  if (!(max_age > 0)) max_age = std::max(3.0, 3.0 * period);
  const double age = now_unix - time;
  if (age > max_age) {
    return bad(path + " is " + fixed("%.1f", age) + " s old (max " + fixed("%g", max_age) +
               " s): the sidecar has stopped updating it (state was " + state + ")");
  }
  if (age < -max_age) {
    return bad(path + " is dated " + fixed("%.1f", -age) + " s in the future: clock jump?");
  }
  if (state != "running" && state != "starting") {
    return bad(state + (reason.empty() ? std::string() : ": " + reason));
  }
  for (int i = 0; i < 3; ++i) {
    if (threads[i] > max_age) {
      return bad(std::string(thread_names[i]) + " thread has not advanced for " +
                 fixed("%.1f", threads[i]) + " s (max " + fixed("%g", max_age) + " s)");
    }
  }
  v.healthy = true;
  v.line = "healthy: " + state + ", updated " + fixed("%.1f", std::max(0.0, age)) + " s ago, " +
           std::to_string(samples) + " samples, inputs " +
           (flags.empty() ? std::string("ok") : flags + " (not a health problem)");
  return v;
}

}  // namespace usvfdi::dds_service
