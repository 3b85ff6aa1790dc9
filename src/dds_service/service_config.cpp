#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "usv_fdi/dds_service/service.hpp"
#include "usv_fdi/io/config.hpp"

#ifndef USV_FDI_DEFAULT_QOS_PROFILES
#define USV_FDI_DEFAULT_QOS_PROFILES ""
#endif

namespace usvfdi::service {
namespace {

using io::ConfigError;

[[noreturn]] void fail(const std::string& file, const YAML::Node& n, const std::string& key,
                       const std::string& why) {
  std::string value;
  try {
    value = n.IsScalar() ? n.Scalar() : (n.IsSequence() ? "<list>" : "<mapping>");
  } catch (...) {
    value = "?";
  }
  throw ConfigError(file + ":" + std::to_string(n.Mark().line + 1) + ": service." + key + " = " +
                    value + ": " + why);
}

template <typename T>
T get(const std::string& file, const YAML::Node& n, const std::string& key, const char* what) {
  if (!n.IsScalar()) fail(file, n, key, std::string("must be ") + what);
  try {
    return n.as<T>();
  } catch (const YAML::Exception&) {
    fail(file, n, key, std::string("must be ") + what);
  }
}

std::vector<std::string> strings(const std::string& file, const YAML::Node& n,
                                 const std::string& key) {
  if (!n.IsSequence()) fail(file, n, key, "must be a list of strings");
  std::vector<std::string> out;
  for (const YAML::Node& e : n) out.push_back(get<std::string>(file, e, key, "a string"));
  return out;
}

}  // namespace

std::string default_qos_profiles() {
  if (const char* env = std::getenv("USV_FDI_QOS_PROFILES")) return env;
  return USV_FDI_DEFAULT_QOS_PROFILES;
}

ServiceConfig load_service_config(const std::string& path) {
  ServiceConfig cfg;
  cfg.config_file = path;
  cfg.engine = io::load_engine_config(path);  // also reports a missing file / bad YAML
  const YAML::Node root = YAML::LoadFile(path);
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  std::string qos = default_qos_profiles();
  cfg.state_dir = kDefaultStateDir;
  const auto relative_to_config = [&](const std::string& p) {
    const std::filesystem::path fp(p);
    return (fp.is_absolute() ? fp : dir / fp).lexically_normal().string();
  };
  const YAML::Node s = root["service"];
  if (s && !s.IsMap()) fail(path, s, "", "must be a mapping");
  bool have_mmsi = false;
  YAML::Node input_timeout_node;
  std::vector<std::pair<std::string, YAML::Node>> topic_nodes;  ///< topics given, in order
  if (s) {
    for (const auto& kv : s) {
      const std::string key = kv.first.as<std::string>();
      const YAML::Node& v = kv.second;
      if (key == "mmsi") {
        const auto m = get<long long>(path, v, key, "an MMSI (1..999999999)");
        if (m < 1 || m > 999999999) fail(path, v, key, "must be an MMSI (1..999999999)");
        cfg.mmsi = static_cast<std::uint32_t>(m);
        have_mmsi = true;
      } else if (key == "domain_id") {
        const auto d = get<long long>(path, v, key, "an integer 0..232");
        if (d < 0 || d > 232) fail(path, v, key, "must be 0..232 (Fast DDS port mapping)");
        cfg.dds.domain_id = static_cast<std::uint32_t>(d);
      } else if (key == "qos_profiles") {
        const auto p = std::filesystem::path(get<std::string>(path, v, key, "a file path"));
        qos = (p.is_absolute() ? p : dir / p).lexically_normal().string();
        if (!std::filesystem::exists(qos)) fail(path, v, key, "no such file: " + qos);
      } else if (key == "participant_profile") {
        cfg.dds.participant_profile = get<std::string>(path, v, key, "a profile name");
      } else if (key == "topics") {
        if (!v.IsMap()) fail(path, v, key, "must be a mapping of topic names");
        for (const auto& t : v) {
          const std::string tk = t.first.as<std::string>();
          const std::string name = get<std::string>(path, t.second, key + "." + tk, "a topic name");
          topic_nodes.emplace_back(tk, t.second);
          if (tk == "ins")
            cfg.dds.topics.ins = name;
          else if (tk == "rudder")
            cfg.dds.topics.rudder = name;
          else if (tk == "fault_event")
            cfg.dds.topics.fault_event = name;
          else if (tk == "fault_ack")
            cfg.dds.topics.fault_ack = name;
          else if (tk == "status")
            cfg.dds.topics.status = name;
          else
            fail(path, t.second, key + "." + tk,
                 "unknown topic (ins, rudder, fault_event, fault_ack, status)");
        }
      } else if (key == "partitions") {
        cfg.dds.publisher_partitions = strings(path, v, key);
        cfg.dds.subscriber_partitions = cfg.dds.publisher_partitions;
      } else if (key == "reliable_inputs") {
        cfg.reliable_inputs = get<bool>(path, v, key, "true or false");
      } else if (key == "status_rate") {
        const double r = get<double>(path, v, key, "a rate in Hz");
        if (!(r > 0) || !std::isfinite(r)) fail(path, v, key, "must be a positive rate in Hz");
        cfg.pipeline.status_period = 1.0 / r;
      } else if (key == "log_level") {
        static const std::set<std::string> levels = {"trace", "debug",    "info", "warn",
                                                     "error", "critical", "off"};
        cfg.log_level = get<std::string>(path, v, key, "a log level");
        if (!levels.count(cfg.log_level)) {
          fail(path, v, key, "must be one of trace, debug, info, warn, error, critical, off");
        }
      } else if (key == "authorised_operators") {
        cfg.pipeline.authorised_operators = strings(path, v, key);
      } else if (key == "input_queue") {
        const auto n = get<long long>(path, v, key, "a queue length");
        if (n < 1 || n > 1000000) fail(path, v, key, "must be 1..1000000");
        cfg.pipeline.input_capacity = static_cast<std::size_t>(n);
      } else if (key == "rudder_wait" || key == "rudder_timeout" || key == "input_timeout" ||
                 key == "restore_recheck") {
        const double x = get<double>(path, v, key, "a time in seconds");
        if (!(x > 0) || !std::isfinite(x)) fail(path, v, key, "must be a positive time in s");
        (key == "rudder_wait"      ? cfg.pipeline.rudder_wait
         : key == "rudder_timeout" ? cfg.pipeline.rudder_timeout
         : key == "input_timeout"  ? cfg.pipeline.input_timeout
                                   : cfg.pipeline.restore_recheck) = x;
        if (key == "input_timeout") input_timeout_node = v;
      } else if (key == "state_dir") {
        // null or "": no persistence.
        const std::string d =
            v.IsNull() ? std::string() : get<std::string>(path, v, key, "a directory");
        cfg.state_dir = d.empty() ? d : relative_to_config(d);
        cfg.state_dir_explicit = true;
        std::error_code ec;
        if (!cfg.state_dir.empty() && std::filesystem::exists(cfg.state_dir, ec) &&
            !std::filesystem::is_directory(cfg.state_dir, ec)) {
          fail(path, v, key, "not a directory: " + cfg.state_dir);
        }
      } else if (key == "health_file") {
        const std::string f =
            v.IsNull() ? std::string() : get<std::string>(path, v, key, "a file path");
        cfg.health_file = f.empty() ? f : relative_to_config(f);
      } else {
        fail(path, kv.first, key, "unknown key");
      }
    }
  }
  (void)have_mmsi;
  // Two roles on one topic name would make the DDS participant fail later (exit 1).
  const std::pair<const char*, const std::string*> topics[] = {
      {"ins", &cfg.dds.topics.ins},
      {"rudder", &cfg.dds.topics.rudder},
      {"fault_event", &cfg.dds.topics.fault_event},
      {"fault_ack", &cfg.dds.topics.fault_ack},
      {"status", &cfg.dds.topics.status}};
  for (std::size_t k = 0; k < topic_nodes.size(); ++k) {  // in the file's order
    const auto& [key, node] = topic_nodes[k];
    for (const auto& [other, name] : topics) {
      if (other == key || *name != node.Scalar()) continue;
      bool later = false;  // `other` is given further down: it is the one to blame
      for (std::size_t j = k + 1; j < topic_nodes.size(); ++j)
        later |= topic_nodes[j].first == other;
      if (!later) {
        fail(path, node, "topics." + key,
             std::string("the same topic name as service.topics.") + other);
      }
    }
  }
  // A silent INS is reported as stale faults: the silence must outlast the stale check.
  if (input_timeout_node && cfg.pipeline.input_timeout < cfg.engine.isolation.stale_timeout) {
    char why[128];
    std::snprintf(why, sizeof why, "must be at least isolation.stale_timeout (%g s)",
                  cfg.engine.isolation.stale_timeout);
    fail(path, input_timeout_node, "input_timeout", why);
  }
  cfg.dds.profiles_file = qos;
  return cfg;
}

}  // namespace usvfdi::service
