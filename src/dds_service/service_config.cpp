#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
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
#include "usv_fdi/nmea/navigation.hpp"

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

namespace {

/// What the handlers of the `service:` section fill in, and what they note for the checks
/// that need the whole file. Lives on load_service_config's stack: the handlers point to it.
struct ServiceLoad {
  ServiceConfig cfg;
  std::string qos;               ///< the QoS profiles file (relative paths resolved)
  std::filesystem::path dir;     ///< the config file's directory
  std::string input_timeout_at;  ///< where service.input_timeout was given ("" : not given)
  std::vector<std::pair<std::string, std::string>> topics_given;  ///< (key, where), in order

  std::string relative_to_config(const std::string& p) const {
    const std::filesystem::path fp(p);
    return (fp.is_absolute() ? fp : dir / fp).lexically_normal().string();
  }
};

ConfigValue::Handler positive_time(double* out) {
  return [out](const ConfigValue& v) {
    *out = v.number(1e-9, 1e9, "a time in seconds", "a positive time in s");
  };
}

/// service.topics: the six topic names, each noted where it was given.
ConfigValue::Table topic_table(ServiceLoad* s) {
  const auto topic = [s](std::string* out) {
    return [s, out](const ConfigValue& v) {
      *out = v.text("a topic name");
      s->topics_given.emplace_back(v.path(), v.where());
    };
  };
  usvfdi::dds::TopicNames& t = s->cfg.dds.topics;
  return {{"ins", topic(&t.ins)},
          {"rudder", topic(&t.rudder)},
          {"fault_event", topic(&t.fault_event)},
          {"fault_ack", topic(&t.fault_ack)},
          {"status", topic(&t.status)},
          {"speed", topic(&t.speed)}};
}

/// service.qos_profiles: readable as a file now, or the operating system's reason (EISDIR:
/// open(2) takes a directory for reading).
void read_qos_profiles(const ConfigValue& v, ServiceLoad* s) {
  s->qos = s->relative_to_config(v.text("a file path"));
  const int fd = ::open(s->qos.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat st {};
  const bool opened = fd >= 0 && ::fstat(fd, &st) == 0;
  const int err = !opened ? errno : S_ISDIR(st.st_mode) ? EISDIR : 0;
  if (fd >= 0) ::close(fd);
  if (err == ENOENT) v.fail("no such file: " + s->qos);
  if (err != 0) v.fail("cannot read " + s->qos + ": " + std::strerror(err));
}

/// service.log_level: one of spdlog's level names.
void read_log_level(const ConfigValue& v, std::string* out) {
  static const std::set<std::string> levels = {"trace", "debug",    "info", "warn",
                                               "error", "critical", "off"};
  *out = v.text("a log level");
  if (!levels.count(*out)) v.fail("must be one of trace, debug, info, warn, error, critical, off");
}

/// service.state_dir: null or "" switches persistence off; an existing path must be a
/// directory.
void read_state_dir(const ConfigValue& v, ServiceLoad* s) {
  const std::string d = v.is_null() ? std::string() : v.text("a directory");
  ServiceConfig& cfg = s->cfg;
  cfg.state_dir = d.empty() ? d : s->relative_to_config(d);
  cfg.state_dir_explicit = true;
  std::error_code ec;
  if (!cfg.state_dir.empty() && std::filesystem::exists(cfg.state_dir, ec) &&
      !std::filesystem::is_directory(cfg.state_dir, ec)) {
    v.fail("not a directory: " + cfg.state_dir);
  }
}

/// The keys of the vessel and its DDS participant: mmsi, domain_id, qos_profiles,
/// participant_profile, topics, partitions, reliable_inputs, content_filter.
void add_dds_keys(ServiceLoad* s, ConfigValue::Table* table) {
  ServiceConfig& cfg = s->cfg;
  ConfigValue::Table& t = *table;
  t["mmsi"] = [&cfg](const ConfigValue& v) {
    cfg.mmsi = static_cast<std::uint32_t>(v.integer(1, 999999999, "an MMSI (1..999999999)"));
  };
  t["domain_id"] = [&cfg](const ConfigValue& v) {
    cfg.dds.domain_id = static_cast<std::uint32_t>(
        v.integer(0, 232, "an integer 0..232", "0..232 (Fast DDS port mapping)"));
  };
  t["qos_profiles"] = [s](const ConfigValue& v) { read_qos_profiles(v, s); };
  t["participant_profile"] = [&cfg](const ConfigValue& v) {
    cfg.dds.participant_profile = v.text("a profile name");
  };
  t["topics"] = [s](const ConfigValue& v) {
    if (v.is_null()) v.fail("must be a mapping of topic names");
    v.section(topic_table(s), "unknown topic", false);
  };
  t["partitions"] = [&cfg](const ConfigValue& v) {
    cfg.dds.publisher_partitions = v.strings();
    cfg.dds.subscriber_partitions = cfg.dds.publisher_partitions;
  };
  t["reliable_inputs"] = [&cfg](const ConfigValue& v) { cfg.reliable_inputs = v.boolean(); };
  t["content_filter"] = [&cfg](const ConfigValue& v) { cfg.content_filter = v.boolean(); };
}

/// The pipeline's keys: estimate_wait, status_rate, authorised_operators, input_queue,
/// rudder_wait, rudder_timeout, speed_max_age, input_timeout, restore_recheck, status_uplink.
void add_pipeline_keys(ServiceLoad* s, ConfigValue::Table* table) {
  pipeline::PipelineOptions& p = s->cfg.pipeline;
  ConfigValue::Table& t = *table;
  t["estimate_wait"] = [&p](const ConfigValue& v) {
    p.estimate_wait = v.number(0.0, 3600.0, "a time in s", "0 to 3600 s");
  };
  t["status_rate"] = [&p](const ConfigValue& v) {
    p.status_period = 1.0 / v.number(1e-9, 1e9, "a rate in Hz", "a positive rate in Hz");
  };
  t["authorised_operators"] = [&p](const ConfigValue& v) { p.authorised_operators = v.strings(); };
  t["input_queue"] = [&p](const ConfigValue& v) {
    p.input_capacity =
        static_cast<std::size_t>(v.integer(1, 1000000, "a queue length", "1..1000000"));
  };
  t["rudder_wait"] = positive_time(&p.rudder_wait);
  t["rudder_timeout"] = positive_time(&p.rudder_timeout);
  t["speed_max_age"] = positive_time(&p.speed_max_age);
  t["input_timeout"] = [s, &p](const ConfigValue& v) {
    positive_time (&p.input_timeout)(v);
    s->input_timeout_at = v.where();
  };
  t["restore_recheck"] = positive_time(&p.restore_recheck);
  t["status_uplink"] = [s](const ConfigValue& v) {
    if (v.is_null()) v.fail("must be a mapping (mode, heartbeat, tolerance, theta, decay)");
    UplinkOptions& u = s->cfg.uplink;
    ConfigValue::Table keys;
    keys["mode"] = [&u](const ConfigValue& a) {
      const std::string m = a.text("event or periodic");
      if (m != "event" && m != "periodic") {
        a.fail(
            "must be event (a status when something changes, and a heartbeat) or periodic "
            "(every status_rate period)");
      }
      u.event = m == "event";
    };
    keys["heartbeat"] = [&u](const ConfigValue& a) {
      u.heartbeat = a.number(1e-3, 3600.0, "a time in s", "0.001 to 3600 s");
    };
    keys["tolerance"] = [&u](const ConfigValue& a) {
      u.tolerance = a.number(1e-6, 10.0, "a relative deviation", "1e-6 to 10");
    };
    keys["theta"] = [&u](const ConfigValue& a) {
      u.theta = a.number(1e-6, 1e12, "a positive weight", "1e-6 to 1e12");
    };
    keys["decay"] = [&u](const ConfigValue& a) {
      u.decay = a.number(0.0, 0.999, "a factor", "0 to 0.999");
    };
    v.section(keys);
  };
}

}  // namespace

bool is_host_port(const std::string& s) {
  const std::size_t colon = s.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == s.size() || colon + 6 < s.size()) {
    return false;
  }
  for (std::size_t i = 0; i < colon; ++i) {
    const char c = s[i];
    const bool ok = std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' ||
                    c == '_' || c == ':' || c == '[' || c == ']';
    if (!ok) return false;
  }
  long port = 0;
  for (std::size_t i = colon + 1; i < s.size(); ++i) {
    if (!std::isdigit(static_cast<unsigned char>(s[i]))) return false;
    port = port * 10 + (s[i] - '0');
  }
  return port <= 65535;
}

namespace {

/// The process's keys: log_level, state_dir, health_file, metrics.
void add_process_keys(ServiceLoad* s, ConfigValue::Table* table) {
  ConfigValue::Table& t = *table;
  t["log_level"] = [s](const ConfigValue& v) { read_log_level(v, &s->cfg.log_level); };
  t["state_dir"] = [s](const ConfigValue& v) { read_state_dir(v, s); };
  t["health_file"] = [s](const ConfigValue& v) {
    const std::string f = v.is_null() ? std::string() : v.text("a file path");
    s->cfg.health_file = f.empty() ? f : s->relative_to_config(f);
  };
  t["metrics"] = [s](const ConfigValue& v) {
    s->cfg.metrics = v.is_null() ? std::string() : v.text("host:port");
    if (!s->cfg.metrics.empty() && !is_host_port(s->cfg.metrics)) {
      v.fail("must be HOST:PORT (an address or name, a port 0-65535; 0: any free port)");
    }
  };
}

/// service.input and service.nmea: the live NMEA 0183 / IEC 61162-450 input over UDP.
void add_input_keys(ServiceLoad* s, ConfigValue::Table* table) {
  ServiceConfig& cfg = s->cfg;
  ConfigValue::Table& t = *table;
  t["input"] = [&cfg](const ConfigValue& v) {
    const std::string in = v.text("dds or nmea");
    if (in == "dds") {
      cfg.input = InputSource::kDds;
    } else if (in == "nmea") {
      cfg.input = InputSource::kNmea;
    } else {
      v.fail("must be dds (InsSample and RudderSample topics) or nmea (NMEA 0183 over UDP)");
    }
  };
  t["nmea"] = [&cfg](const ConfigValue& v) {
    if (v.is_null()) v.fail("must be a mapping (address, port, interface, rate, ...)");
    nmea_udp::ReceiverConfig& n = cfg.nmea;
    const auto address = [](const ConfigValue& a, bool empty_ok) {
      const std::string text = a.is_null() ? std::string() : a.text("an IPv4 address");
      if (text.empty() && empty_ok) return text;
      try {
        nmea_udp::is_multicast(text);
      } catch (const std::invalid_argument& e) {
        a.fail(e.what());
      }
      return text;
    };
    ConfigValue::Table keys;
    keys["address"] = [&n, address](const ConfigValue& a) {
      n.endpoint.address = address(a, false);
    };
    keys["port"] = [&n](const ConfigValue& a) {
      n.endpoint.port = static_cast<std::uint16_t>(a.integer(1, 65535, "a UDP port (1..65535)"));
    };
    keys["interface"] = [&n, address](const ConfigValue& a) {
      n.interface_address = address(a, true);
    };
    keys["rate"] = [&n](const ConfigValue& a) {
      n.assembler.rate_hz = a.number(1e-3, 1e4, "a rate in Hz", "0.001 to 10000 Hz");
    };
    keys["max_age"] = positive_time(&n.assembler.max_age_s);
    keys["hold_until_due"] = [&n](const ConfigValue& a) {
      n.assembler.hold_until_due = a.boolean();
    };
    keys["receive_buffer"] = [&n](const ConfigValue& a) {
      n.receive_buffer =
          static_cast<int>(a.integer(0, 1 << 30, "a size in bytes", "0..1073741824 bytes"));
    };
    v.section(keys);
  };
}

/// A silent INS is reported as stale faults: the silence must outlast the stale check.
void check_input_timeout(const ServiceLoad& s) {
  if (s.input_timeout_at.empty() ||
      s.cfg.pipeline.input_timeout >= s.cfg.engine.isolation.stale_timeout) {
    return;
  }
  char why[128];
  std::snprintf(why, sizeof why, ": must be at least isolation.stale_timeout (%g s)",
                s.cfg.engine.isolation.stale_timeout);
  throw ConfigError(s.input_timeout_at + why);
}

/// Two roles on one topic name would make the DDS participant fail later (exit 1); the one
/// given last in the file is named.
void check_distinct_topics(const ServiceLoad& s) {
  const usvfdi::dds::TopicNames& t = s.cfg.dds.topics;
  const std::pair<const char*, const std::string*> names[] = {{"ins", &t.ins},
                                                              {"rudder", &t.rudder},
                                                              {"fault_event", &t.fault_event},
                                                              {"fault_ack", &t.fault_ack},
                                                              {"status", &t.status},
                                                              {"speed", &t.speed}};
  const auto& given = s.topics_given;
  for (std::size_t k = 0; k < given.size(); ++k) {
    const std::string key = given[k].first.substr(given[k].first.rfind('.') + 1);
    const std::string& name = *std::find_if(std::begin(names), std::end(names), [&](const auto& n) {
                                 return key == n.first;
                               })->second;
    for (const auto& [other, other_name] : names) {
      if (key == other || *other_name != name) continue;
      bool later = false;  // `other` is given further down: it is the one to name
      for (std::size_t j = k + 1; j < given.size(); ++j) {
        later |= given[j].first == "service.topics." + std::string(other);
      }
      if (!later) {
        throw ConfigError(given[k].second + ": the same topic name as service.topics." + other);
      }
    }
  }
}

}  // namespace

ServiceConfig load_service_config(const std::string& path) {
  ServiceLoad s;
  s.cfg.config_file = path;
  s.cfg.state_dir = kDefaultStateDir;
  s.qos = default_qos_profiles();
  s.dir = std::filesystem::path(path).parent_path();
  ConfigValue::Table service;
  add_dds_keys(&s, &service);
  add_pipeline_keys(&s, &service);
  add_process_keys(&s, &service);
  add_input_keys(&s, &service);
  // One reading of the file: the engine's keys and, by these handlers, the service section.
  s.cfg.engine = io::load_engine_config(
      path, {{"service", [&service](const ConfigValue& v) { v.section(service); }}});
  check_input_timeout(s);
  check_distinct_topics(s);
  s.cfg.dds.profiles_file = s.qos;
  s.cfg.nmea.assembler.rudder_sign = nmea::rudder_sign_from_b2(s.cfg.engine.B(1));
  return std::move(s.cfg);
}

}  // namespace usvfdi::dds_service
