#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
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

namespace usvfdi::dds_service {

using io::ConfigError;
using io::ConfigValue;

std::string default_qos_profiles() {
  if (const char* env = std::getenv("USV_FDI_QOS_PROFILES")) return env;
  return USV_FDI_DEFAULT_QOS_PROFILES;
}

ServiceConfig load_service_config(const std::string& path) {
  ServiceConfig cfg;
  cfg.config_file = path;
  cfg.state_dir = kDefaultStateDir;
  std::string qos = default_qos_profiles();
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  const auto relative_to_config = [&dir](const std::string& p) {
    const std::filesystem::path fp(p);
    return (fp.is_absolute() ? fp : dir / fp).lexically_normal().string();
  };
  std::string input_timeout_at;  ///< where service.input_timeout was given ("" : not given)
  std::vector<std::pair<std::string, std::string>> topics_given;  ///< (key, where), in order
  const auto positive_time = [](double* out) {
    return [out](const ConfigValue& v) {
      *out = v.number(1e-9, 1e9, "a time in seconds", "a positive time in s");
    };
  };
  const auto topic = [&topics_given](std::string* out) {
    return [out, &topics_given](const ConfigValue& v) {
      *out = v.text("a topic name");
      topics_given.emplace_back(v.path(), v.where());
    };
  };
  const ConfigValue::Table topics = {
      {"ins", topic(&cfg.dds.topics.ins)},
      {"rudder", topic(&cfg.dds.topics.rudder)},
      {"fault_event", topic(&cfg.dds.topics.fault_event)},
      {"fault_ack", topic(&cfg.dds.topics.fault_ack)},
      {"status", topic(&cfg.dds.topics.status)},
  };
  const ConfigValue::Table service = {
      {"mmsi",
       [&](const ConfigValue& v) {
         cfg.mmsi = static_cast<std::uint32_t>(v.integer(1, 999999999, "an MMSI (1..999999999)"));
       }},
      {"domain_id",
       [&](const ConfigValue& v) {
         cfg.dds.domain_id = static_cast<std::uint32_t>(
             v.integer(0, 232, "an integer 0..232", "0..232 (Fast DDS port mapping)"));
       }},
      {"qos_profiles",
       [&](const ConfigValue& v) {
         qos = relative_to_config(v.text("a file path"));
         // Readable as a file now, or the operating system's reason (EISDIR: open(2) takes a
         // directory for reading).
         const int fd = ::open(qos.c_str(), O_RDONLY | O_CLOEXEC);
         struct stat st {};
         const bool opened = fd >= 0 && ::fstat(fd, &st) == 0;
         const int err = !opened ? errno : S_ISDIR(st.st_mode) ? EISDIR : 0;
         if (fd >= 0) ::close(fd);
         if (err == ENOENT) v.fail("no such file: " + qos);
         if (err != 0) v.fail("cannot read " + qos + ": " + std::strerror(err));
       }},
      {"participant_profile",
       [&](const ConfigValue& v) { cfg.dds.participant_profile = v.text("a profile name"); }},
      {"topics",
       [&](const ConfigValue& v) {
         if (v.is_null()) v.fail("must be a mapping of topic names");
         v.section(topics, "unknown topic", false);
       }},
      {"partitions",
       [&](const ConfigValue& v) {
         cfg.dds.publisher_partitions = v.strings();
         cfg.dds.subscriber_partitions = cfg.dds.publisher_partitions;
       }},
      {"reliable_inputs", [&](const ConfigValue& v) { cfg.reliable_inputs = v.boolean(); }},
      {"estimate_wait",
       [&](const ConfigValue& v) {
         cfg.pipeline.estimate_wait = v.number(0.0, 3600.0, "a time in s", "0 to 3600 s");
       }},
      {"status_rate",
       [&](const ConfigValue& v) {
         cfg.pipeline.status_period =
             1.0 / v.number(1e-9, 1e9, "a rate in Hz", "a positive rate in Hz");
       }},
      {"log_level",
       [&](const ConfigValue& v) {
         static const std::set<std::string> levels = {"trace", "debug",    "info", "warn",
                                                      "error", "critical", "off"};
         cfg.log_level = v.text("a log level");
         if (!levels.count(cfg.log_level)) {
           v.fail("must be one of trace, debug, info, warn, error, critical, off");
         }
       }},
      {"authorised_operators",
       [&](const ConfigValue& v) { cfg.pipeline.authorised_operators = v.strings(); }},
      {"input_queue",
       [&](const ConfigValue& v) {
         cfg.pipeline.input_capacity =
             static_cast<std::size_t>(v.integer(1, 1000000, "a queue length", "1..1000000"));
       }},
      {"rudder_wait", positive_time(&cfg.pipeline.rudder_wait)},
      {"rudder_timeout", positive_time(&cfg.pipeline.rudder_timeout)},
      {"input_timeout",
       [&](const ConfigValue& v) {
         positive_time (&cfg.pipeline.input_timeout)(v);
         input_timeout_at = v.where();
       }},
      {"restore_recheck", positive_time(&cfg.pipeline.restore_recheck)},
      {"state_dir",
       [&](const ConfigValue& v) {
         // null or "": no persistence.
         const std::string d = v.is_null() ? std::string() : v.text("a directory");
         cfg.state_dir = d.empty() ? d : relative_to_config(d);
         cfg.state_dir_explicit = true;
         std::error_code ec;
         if (!cfg.state_dir.empty() && std::filesystem::exists(cfg.state_dir, ec) &&
             !std::filesystem::is_directory(cfg.state_dir, ec)) {
           v.fail("not a directory: " + cfg.state_dir);
         }
       }},
      {"health_file",
       [&](const ConfigValue& v) {
         const std::string f = v.is_null() ? std::string() : v.text("a file path");
         cfg.health_file = f.empty() ? f : relative_to_config(f);
       }},
  };
  cfg.engine = io::load_engine_config(
      path, {{"service", [&service](const ConfigValue& v) { v.section(service); }}});

  // A silent INS is reported as stale faults: the silence must outlast the stale check.
  if (!input_timeout_at.empty() &&
      cfg.pipeline.input_timeout < cfg.engine.isolation.stale_timeout) {
    char why[128];
    std::snprintf(why, sizeof why, ": must be at least isolation.stale_timeout (%g s)",
                  cfg.engine.isolation.stale_timeout);
    throw ConfigError(input_timeout_at + why);
  }
  // Two roles on one topic name would make the DDS participant fail later (exit 1); the one
  // given last in the file is named.
  const std::pair<const char*, const std::string*> names[] = {
      {"ins", &cfg.dds.topics.ins},
      {"rudder", &cfg.dds.topics.rudder},
      {"fault_event", &cfg.dds.topics.fault_event},
      {"fault_ack", &cfg.dds.topics.fault_ack},
      {"status", &cfg.dds.topics.status}};
  for (std::size_t k = 0; k < topics_given.size(); ++k) {
    const std::string key = topics_given[k].first.substr(topics_given[k].first.rfind('.') + 1);
    const std::string& name = *std::find_if(std::begin(names), std::end(names), [&](const auto& n) {
                                 return key == n.first;
                               })->second;
    for (const auto& [other, other_name] : names) {
      if (key == other || *other_name != name) continue;
      bool later = false;  // `other` is given further down: it is the one to name
      for (std::size_t j = k + 1; j < topics_given.size(); ++j) {
        later |= topics_given[j].first == "service.topics." + std::string(other);
      }
      if (!later) {
        throw ConfigError(topics_given[k].second + ": the same topic name as service.topics." +
                          other);
      }
    }
  }
  cfg.dds.profiles_file = qos;
  return cfg;
}

}  // namespace usvfdi::dds_service
