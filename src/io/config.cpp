#include "usv_fdi/io/config.hpp"

#include <sys/stat.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace usvfdi::io {
namespace {
class Loader;
}  // namespace

struct ConfigValue::Impl {
  const Loader* loader;
  YAML::Node node;
  std::string path;
};

namespace {

/// Short, single-line rendering of a node for error messages.
std::string render(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "null";
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  YAML::Emitter e;
  e.SetSeqFormat(YAML::Flow);
  e.SetMapFormat(YAML::Flow);
  e << node;
  std::string s = e.c_str();
  for (char& c : s) {
    if (c == '\n') c = ' ';
  }
  if (s.size() > 80) s = s.substr(0, 77) + "...";
  return s;
}

const char* type_name(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "null";
  if (node.IsScalar()) return "a scalar";
  if (node.IsSequence()) return "a list";
  return "a mapping";
}

std::string format_number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

/// The values a number may take [lo, hi], and its unit for messages.
struct Range {
  double lo = -std::numeric_limits<double>::max();
  double hi = std::numeric_limits<double>::max();
  const char* unit = "";
  /// " [lo, hi] unit", or "" for any finite number.
  std::string text() const {
    if (lo == -std::numeric_limits<double>::max() && hi == std::numeric_limits<double>::max()) {
      return "";
    }
    return " [" + format_number(lo) + ", " + format_number(hi) + "]" +
           (*unit ? std::string(" ") + unit : std::string());
  }
};
const Range kAnything{};
constexpr double kHour = 3600.0;  ///< [s]

/// Parses one YAML document into an EngineConfig; every problem names file, key, line, value.
class Loader {
 public:
  explicit Loader(std::string file, const ConfigValue::Table* extra = nullptr)
      : file_(std::move(file)), extra_(extra) {}
  const std::string& file() const { return file_; }

  [[noreturn]] void fail(const YAML::Node& node, const std::string& path,
                         const std::string& reason) const {
    std::ostringstream os;
    os << file_;
    if (node.IsDefined() && node.Mark().line >= 0) os << ":" << node.Mark().line + 1;
    os << ": " << (path.empty() ? "(document)" : path) << " = " << render(node) << ": " << reason;
    throw ConfigError(os.str());
  }

  [[noreturn]] void fail_missing(const YAML::Node& parent, const std::string& path) const {
    std::ostringstream os;
    os << file_;
    if (parent.IsDefined() && parent.Mark().line >= 0) os << ":" << parent.Mark().line + 1;
    os << ": " << path << ": required key missing (e.g. `B: [0.165, -2.19]` under `model:`)";
    throw ConfigError(os.str());
  }

  double number(const YAML::Node& n, const std::string& path, const Range& range = kAnything) {
    remember(n, path);
    if (!n.IsScalar()) fail(n, path, std::string("expected a number, got ") + type_name(n));
    double x = 0.0;
    if (!YAML::convert<double>::decode(n, x)) fail(n, path, "expected a number");
    if (!std::isfinite(x)) fail(n, path, "must be a finite number" + range.text());
    checks_.push_back({n, path, x, range});
    return x;
  }

  int integer(const YAML::Node& n, const std::string& path, const Range& range = kAnything) {
    remember(n, path);
    if (!n.IsScalar()) fail(n, path, std::string("expected an integer, got ") + type_name(n));
    int x = 0;
    if (!YAML::convert<int>::decode(n, x)) fail(n, path, "expected an integer");
    checks_.push_back({n, path, static_cast<double>(x), range});
    return x;
  }

  bool boolean(const YAML::Node& n, const std::string& path) {
    remember(n, path);
    if (!n.IsScalar()) fail(n, path, std::string("expected true or false, got ") + type_name(n));
    bool x = false;
    if (!YAML::convert<bool>::decode(n, x)) fail(n, path, "expected true or false");
    return x;
  }

  std::string text(const YAML::Node& n, const std::string& path) {
    remember(n, path);
    if (!n.IsScalar()) fail(n, path, std::string("expected a string, got ") + type_name(n));
    return n.Scalar();
  }

  template <int N>
  Eigen::Matrix<double, N, 1> vector(const YAML::Node& n, const std::string& path,
                                     const Range& range = kAnything) {
    remember(n, path);
    if (!n.IsSequence() || n.size() != static_cast<std::size_t>(N)) {
      fail(n, path,
           "expected a list of " + std::to_string(N) + " numbers, got " +
               (n.IsSequence() ? "a list of " + std::to_string(n.size())
                               : std::string(type_name(n))));
    }
    Eigen::Matrix<double, N, 1> v;
    for (int i = 0; i < N; ++i) {
      v(i) = number(n[i], path + "[" + std::to_string(i) + "]", range);
    }
    remember(n, path);  // the element paths must not shadow the list's own mark
    return v;
  }

  using Handler = std::function<void(const YAML::Node&, const std::string&)>;

  /// Walks a mapping, dispatching every key to its handler; unknown keys are errors.
  void section(const YAML::Node& node, const std::string& path,
               const std::map<std::string, Handler>& handlers) {
    remember(node, path);
    if (!node.IsDefined() || node.IsNull()) return;  // `identification:` with nothing under it
    if (!node.IsMap()) fail(node, path, std::string("expected a mapping, got ") + type_name(node));
    std::set<std::string> keys;
    for (const auto& kv : node) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : render(kv.first);
      const std::string sub = path.empty() ? key : path + "." + key;
      if (!keys.insert(key).second) fail(kv.second, sub, "key given twice");
      const auto it = handlers.find(key);
      if (it == handlers.end()) {
        std::string allowed;
        for (const auto& h : handlers) allowed += (allowed.empty() ? "" : ", ") + h.first;
        YAML::Node where =
            kv.second.IsDefined() && kv.second.Mark().line >= 0 ? kv.second : kv.first;
        fail(where, sub, "unknown key (expected one of: " + allowed + ")");
      }
      it->second(kv.second, sub);
    }
  }

  EngineConfig load(const YAML::Node& root) {
    EngineConfig cfg;
    bool have_b = false;
    const Keys model = model_keys(&cfg, &have_b);
    const Keys identification = identification_keys(&cfg);
    const Keys isolation = isolation_keys(&cfg.isolation);
    const Keys jump = jump_keys(&cfg.isolation.jump);
    const Keys speed = speed_keys(&cfg.speed);
    const Keys top = document_keys(model, identification, isolation, jump, speed);

    if (!root.IsDefined() || root.IsNull()) fail_missing(root, "model.B");
    section(root, "", top);
    if (!have_b) fail_missing(root["model"].IsDefined() ? root["model"] : root, "model.B");
    validate_and_check_ranges(cfg);
    return cfg;
  }

 private:
  using Keys = std::map<std::string, Handler>;

  // Handlers that parse a value into *out. Each number gets the range within which the
  // engine still detects (checked after the engine's own validate(), whose messages explain
  // the finer rules).
  Handler number_into(double* out, Range r) {
    return [this, out, r](const YAML::Node& n, const std::string& p) { *out = number(n, p, r); };
  }
  Handler integer_into(int* out, Range r) {
    return [this, out, r](const YAML::Node& n, const std::string& p) { *out = integer(n, p, r); };
  }
  Handler boolean_into(bool* out) {
    return [this, out](const YAML::Node& n, const std::string& p) { *out = boolean(n, p); };
  }
  Handler vector2_into(Vec2* out, Range r) {
    return [this, out, r](const YAML::Node& n, const std::string& p) { *out = vector<2>(n, p, r); };
  }
  /// One of a few names, each standing for a value ("expected a or b" otherwise).
  template <typename T>
  Handler choice_into(T* out, std::vector<std::pair<std::string, T>> names) {
    return [this, out, names](const YAML::Node& n, const std::string& p) {
      const std::string m = text(n, p);
      std::string expected;
      for (std::size_t i = 0; i < names.size(); ++i) {
        if (names[i].first == m) {
          *out = names[i].second;
          return;
        }
        expected += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i].first;
      }
      fail(n, p, "expected " + expected);
    };
  }

  /// `model:`; sets *have_b when B is given.
  Keys model_keys(EngineConfig* cfg, bool* have_b) {
    return {
        {"B",
         [this, cfg, have_b](const YAML::Node& n, const std::string& p) {
           cfg->B = vector<2>(n, p, {-1e3, 1e3, "(b1 in m/s^2, b2 in 1/s^2, per rad of rudder)"});
           *have_b = true;
         }},
        {"A0",
         [this, cfg](const YAML::Node& n, const std::string& p) {
           cfg->identification.a0 = vector<4>(n, p, {-1e3, 1e3, "1/s"});
           remember(n, "identification.a0");  // the name validate() uses
         }},
        {"reference_speed",
         number_into(&cfg->speed.reference_speed, {0, 1e3, "m/s (0: the first measured speed)"})},
    };
  }

  Keys speed_keys(SpeedParams* speed) {
    return {
        {"min_ratio", number_into(&speed->min_ratio, {0, 1e3, ""})},
        {"max_ratio", number_into(&speed->max_ratio, {0, 1e3, ""})},
        {"quantum", number_into(&speed->quantum, {0, 1, ""})},
        {"input_exponent", number_into(&speed->input_exponent, {0, 3, ""})},
    };
  }

  /// `identification:` (IdentificationParams, and the engine's identification delay).
  Keys identification_keys(EngineConfig* cfg) {
    IdentificationParams& id = cfg->identification;
    return {
        {"method", choice_into(&id.method, {{"kreisselmeier", IdentMethod::kKreisselmeier},
                                            {"paper", IdentMethod::kPaper}})},
        {"instruments", choice_into(&id.instruments, {{"rudder", Instruments::kRudder},
                                                      {"regressor", Instruments::kRegressor}})},
        {"precision", choice_into(&id.precision, {{"coefficients", Precision::kCoefficients},
                                                  {"prediction", Precision::kPrediction}})},
        {"eps1", number_into(&id.eps1, {1e-3, 1e3, "1/s"})},
        {"eps2", number_into(&id.eps2, {1e-3, 1e3, "1/s"})},
        {"gamma", number_into(&id.gamma, {0, 1e15, "1/s (paper law: 1/(psi^2 s))"})},
        {"normalised", boolean_into(&id.normalised)},
        {"mu", number_into(&id.mu, {0, 1e3, "excitation^2"})},
        {"lambda", number_into(&id.lambda, {0, 10, "1/s"})},
        {"warmup_time", number_into(&id.warmup_time, {-1e6, kHour, "s (< 0: automatic)"})},
        {"max_gap", number_into(&id.max_gap, {0, kHour, "s"})},
        {"prefilter", number_into(&id.prefilter, {0, 1e3, "rad/s (0: none)"})},
        {"curvature_correction", boolean_into(&id.curvature_correction)},
        {"cubic_correction", boolean_into(&id.cubic_correction)},
        {"min_excitation", number_into(&id.min_excitation, {0, 1, ""})},
        {"settle_window", number_into(&id.settle_window, {0, kHour, "s"})},
        {"settle_tolerance", number_into(&id.settle_tolerance, {0, 1, ""})},
        {"settle_windows", integer_into(&id.settle_windows, {1, 1000, ""})},
        {"settle_floor", number_into(&id.settle_floor, {0, 1e3, "(unit of a_n)"})},
        {"max_std_error", number_into(&id.max_std_error, {0, 10, ""})},
        {"max_prediction_error", number_into(&id.max_prediction_error, {0, 10, ""})},
        {"uncertain_ratio", number_into(&id.uncertain_ratio, {0, 1e6, ""})},
        {"uncertain_time", number_into(&id.uncertain_time, {0, kHour, "s"})},
        {"guard", boolean_into(&id.guard)},
        {"guard_threshold", number_into(&id.guard_threshold, {0, 1e6, ""})},
        {"guard_min_shift", number_into(&id.guard_min_shift, {0, 10, ""})},
        {"guard_recent_time", number_into(&id.guard_recent_time, {0, 100 * kHour, "s"})},
        {"delay", number_into(&cfg->identification_delay, {0, 60, "s"})},
    };
  }

  /// `isolation:` (IsolationParams but its jump check, which has a section of its own).
  Keys isolation_keys(IsolationParams* is) {
    return {
        {"poles_v", vector2_into(&is->poles_v, {-1e3, 0, "1/s"})},
        {"poles_g", vector2_into(&is->poles_g, {-1e3, 0, "1/s"})},
        {"min_observability", number_into(&is->min_observability, {0, 1, ""})},
        {"redesign_tolerance", number_into(&is->redesign_tolerance, {0, 10, ""})},
        {"sigma_v", number_into(&is->sigma_v, {0, 20, "m/s"})},
        {"sigma_r", number_into(&is->sigma_r, {0, 3, "rad/s"})},
        {"sigma_floor_v", number_into(&is->sigma_floor_v, {0, 20, "m/s"})},
        {"sigma_floor_r", number_into(&is->sigma_floor_r, {0, 3, "rad/s"})},
        {"settle_time", number_into(&is->settle_time, {-1e6, kHour, "s (< 0: automatic)"})},
        {"learn_time", number_into(&is->learn_time, {0, 24 * kHour, "s"})},
        {"window", number_into(&is->window, {0, 600, "s"})},
        {"min_window_samples", integer_into(&is->min_window_samples, {1, 1000000, ""})},
        {"clip", number_into(&is->clip, {0, 1e3, ""})},
        {"threshold",
         number_into(&is->threshold,
                     {0, 1e3, "(whitened mean square; at most 0.75 clip^2 takes effect)"})},
        {"threshold_margin", number_into(&is->threshold_margin, {0, 100, ""})},
        {"threshold_k", number_into(&is->threshold_k, {0, 1e3, ""})},
        {"history_margin", number_into(&is->history_margin, {1, 100, ""})},
        {"history", number_into(&is->history, {10, 100 * kHour, "s"})},
        {"exit_ratio", number_into(&is->exit_ratio, {0, 1, ""})},
        {"enter_time", number_into(&is->enter_time, {0, 60, "s"})},
        {"young_enter_ratio", number_into(&is->young_enter_ratio, {1, 100, ""})},
        {"onset_lookback", number_into(&is->onset_lookback, {0, 600, "s"})},
        {"close_capped_bars", boolean_into(&is->close_capped_bars)},
        {"relearn_after_raise", boolean_into(&is->relearn_after_raise)},
        {"on_lost_convergence",
         choice_into(&is->on_lost_convergence, {{"unarm", LostConvergence::kUnarm},
                                                {"hold", LostConvergence::kHold},
                                                {"follow", LostConvergence::kFollow}})},
        {"leave_time", number_into(&is->leave_time, {0, kHour, "s"})},
        {"second_fault_time", number_into(&is->second_fault_time, {0, kHour, "s"})},
        {"mismatch_window", number_into(&is->mismatch_window, {0, kHour, "s"})},
        {"min_active_time", number_into(&is->min_active_time, {0, kHour, "s"})},
        {"c_min", number_into(&is->c_min, {0, 1, ""})},
        {"c_margin", number_into(&is->c_margin, {0, 1, ""})},
        {"resume_time", number_into(&is->resume_time, {0, kHour, "s"})},
        {"resume_after_fault", number_into(&is->resume_after_fault, {0, kHour, "s"})},
        {"stale_timeout", number_into(&is->stale_timeout, {0, kHour, "s"})},
        {"stuck_time", number_into(&is->stuck_time, {0, kHour, "s"})},
        {"stuck_min_samples", integer_into(&is->stuck_min_samples, {1, 1000000, ""})},
        {"stuck_probability", number_into(&is->stuck_probability, {0, 1, ""})},
        {"stuck_learn_time", number_into(&is->stuck_learn_time, {0, 1e6, "s"})},
        {"stuck_time_max", number_into(&is->stuck_time_max, {0, kHour, "s"})},
        {"max_abs_v", number_into(&is->max_abs_v, {0, 1e3, "m/s"})},
        {"max_abs_r", number_into(&is->max_abs_r, {0, 100, "rad/s"})},
        {"max_abs_delta", number_into(&is->max_abs_delta, {0, 6.3, "rad"})},
        {"spike_gate", number_into(&is->spike_gate, {0, 1e3, ""})},
        {"spike_window", number_into(&is->spike_window, {0, kHour, "s"})},
        {"spike_count", integer_into(&is->spike_count, {1, 1000000, ""})},
        {"invalid_count", integer_into(&is->invalid_count, {1, 1000000, ""})},
        {"classify_window", number_into(&is->classify_window, {0, kHour, "s"})},
        {"drift_check", boolean_into(&is->drift_check)},
        {"drift_k", number_into(&is->drift_k, {0, 100, "(whitened)"})},
        {"drift_threshold", number_into(&is->drift_threshold, {0, 1e6, "(whitened x s)"})},
        {"drift_lag", number_into(&is->drift_lag, {0, kHour, "s"})},
        {"drift_min_history", number_into(&is->drift_min_history, {0, 24 * kHour, "s"})},
    };
  }

  /// `jump:` (IsolationParams::jump).
  Keys jump_keys(JumpParams* jp) {
    return {
        {"enabled", boolean_into(&jp->enabled)},
        {"pre_window", number_into(&jp->pre_window, {0, 60, "s"})},
        {"post_window", number_into(&jp->post_window, {0, 60, "s"})},
        {"min_samples", integer_into(&jp->min_samples, {3, 10000, ""})},
        {"persist_samples", integer_into(&jp->persist_samples, {1, 10000, ""})},
        {"persist_time", number_into(&jp->persist_time, {0, 60, "s"})},
        {"threshold", number_into(&jp->threshold, {1, 1e6, ""})},
        {"noise_threshold", number_into(&jp->noise_threshold, {1, 1e6, ""})},
        {"margin", number_into(&jp->margin, {1, 100, ""})},
        {"noise_window", number_into(&jp->noise_window, {0, 60, "s"})},
        {"noise_min_samples", integer_into(&jp->noise_min_samples, {4, 10000, ""})},
        {"learn_time", number_into(&jp->learn_time, {0, 24 * kHour, "s"})},
        {"history", number_into(&jp->history, {10, 100 * kHour, "s"})},
        {"scale_time", number_into(&jp->scale_time, {0, 24 * kHour, "s"})},
        {"leave_time", number_into(&jp->leave_time, {0, kHour, "s"})},
        {"exit_ratio", number_into(&jp->exit_ratio, {0, 1, ""})},
        {"hold_max", number_into(&jp->hold_max, {0, 100 * kHour, "s"})},
        {"max_gap", number_into(&jp->max_gap, {0, kHour, "s"})},
        {"b_uncertainty", number_into(&jp->b_uncertainty, {0, 100, ""})},
        {"rudder_lag", number_into(&jp->rudder_lag, {0, 60, "s"})},
        {"bend_margin", number_into(&jp->bend_margin, {0, 100, "-"})},
        {"bend_rate", number_into(&jp->bend_rate, {0, 100, "1/s"})},
    };
  }

  /// The document's top level: the sections above, `service:` (any mapping unless `extra`
  /// parses it) and every section of `extra`. The sections must outlive the result.
  Keys document_keys(const Keys& model, const Keys& identification, const Keys& isolation,
                     const Keys& jump, const Keys& speed) {
    const auto sub = [this](const Keys& h) {
      return [this, &h](const YAML::Node& n, const std::string& p) { section(n, p, h); };
    };
    Keys top = {
        {"model", sub(model)},
        {"identification", sub(identification)},
        {"isolation", sub(isolation)},
        {"jump", sub(jump)},
        {"speed", sub(speed)},
        // Parsed by the DDS service (through `extra`); otherwise accepted as any mapping.
        {"service",
         [this](const YAML::Node& n, const std::string& p) {
           remember(n, p);
           if (n.IsDefined() && !n.IsNull() && !n.IsMap()) {
             fail(n, p, std::string("expected a mapping, got ") + type_name(n));
           }
         }},
    };
    if (extra_ != nullptr) {
      for (const auto& [key, handler] : *extra_) {
        top[key] = [this, h = handler](const YAML::Node& n, const std::string& p) {
          const ConfigValue::Impl impl{this, n, p};
          h(ConfigValue(&impl));
        };
      }
    }
    return top;
  }

  /// The engine's validate() (its message located in the file), then every number's range.
  void validate_and_check_ranges(const EngineConfig& cfg) const {
    try {
      cfg.validate();
    } catch (const std::invalid_argument& e) {
      throw ConfigError(locate(e.what()));
    }
    for (const Check& c : checks_) {
      if (c.value < c.range.lo || c.value > c.range.hi) {
        fail(c.node, c.path, "outside the allowed range" + c.range.text());
      }
    }
  }
  void remember(const YAML::Node& n, const std::string& path) {
    if (n.IsDefined() && n.Mark().line >= 0) seen_[path] = {n.Mark().line + 1, render(n)};
  }

  /// A validate() message ("<key.path> = <value>: <reason>") prefixed with "file:line: " and
  /// followed by the value as written in the file, for the longest key path it starts with.
  std::string locate(const std::string& message) const {
    std::string best;
    const Seen* where = nullptr;
    for (const auto& [path, seen] : seen_) {
      if (path.size() > best.size() && message.compare(0, path.size(), path) == 0) {
        const char next = message.size() > path.size() ? message[path.size()] : ' ';
        if (next == ' ' || next == '=' || next == ':') {
          best = path;
          where = &seen;
        }
      }
    }
    if (where == nullptr) return file_ + ": " + message + " (default value)";
    std::string m = message;
    if (best == "identification.a0") m = "model.A0" + m.substr(best.size());  // its YAML key
    return file_ + ":" + std::to_string(where->line) + ": " + m + " (in the file: " + where->text +
           ")";
  }

  struct Check {  ///< a number to hold to its range once validate() has passed
    YAML::Node node;
    std::string path;
    double value;
    Range range;
  };
  std::vector<Check> checks_;
  struct Seen {
    int line = 0;      ///< 1-based
    std::string text;  ///< the value as written
  };
  std::string file_;
  const ConfigValue::Table* extra_ = nullptr;
  std::map<std::string, Seen> seen_;
};

EngineConfig load_node(const std::string& name, const std::function<YAML::Node()>& parse,
                       const ConfigValue::Table* extra = nullptr) {
  YAML::Node root;
  try {
    root = parse();
  } catch (const YAML::ParserException& e) {
    std::ostringstream os;
    os << name;
    if (e.mark.line >= 0) os << ":" << e.mark.line + 1 << ":" << e.mark.column + 1;
    os << ": YAML syntax error: " << e.msg;
    throw ConfigError(os.str());
  } catch (const YAML::Exception& e) {
    throw ConfigError(name + ": " + e.what());
  }
  try {
    return Loader(name, extra).load(root);
  } catch (const ConfigError&) {
    throw;
  } catch (const YAML::Exception& e) {  // defensive: a yaml-cpp surprise still names the file
    throw ConfigError(name + ": " + e.what());
  }
}

/// The one document of a YAML text (a second one is an error: it would be ignored).
YAML::Node single_document(const std::string& yaml, const std::string& name) {
  std::vector<YAML::Node> docs = YAML::LoadAll(yaml);
  if (docs.size() > 1) {
    std::string where = name;
    if (docs[1].Mark().line >= 0) where += ":" + std::to_string(docs[1].Mark().line + 1);
    throw ConfigError(where + ": a second YAML document (after '---'): one file holds one " +
                      "configuration");
  }
  return docs.empty() ? YAML::Node() : docs[0];
}

std::string read_file(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    throw ConfigError(path + ": cannot read: " + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) throw ConfigError(path + ": not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path + ": cannot open for reading: " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError(path + ": read error: " + std::strerror(errno));
  return text.str();
}

/// A value as the service's messages show it: the scalar as written, <list>, <mapping>.
std::string plain(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return "null";
  if (n.IsScalar()) return n.Scalar();
  return n.IsSequence() ? "<list>" : "<mapping>";
}

}  // namespace

const std::string& ConfigValue::path() const { return impl_->path; }

bool ConfigValue::is_null() const { return !impl_->node.IsDefined() || impl_->node.IsNull(); }

std::string ConfigValue::where() const {
  const YAML::Node& n = impl_->node;
  std::string w = impl_->loader->file();
  if (n.IsDefined() && n.Mark().line >= 0) w += ":" + std::to_string(n.Mark().line + 1);
  return w + ": " + impl_->path + " = " + plain(n);
}

void ConfigValue::fail(const std::string& reason) const {
  throw ConfigError(where() + ": " + reason);
}

double ConfigValue::number(double lo, double hi, const std::string& what,
                           const std::string& range) const {
  double x = 0.0;
  if (!impl_->node.IsScalar() || !YAML::convert<double>::decode(impl_->node, x) ||
      !std::isfinite(x)) {
    fail("must be " + what);
  }
  if (x < lo || x > hi) fail("must be " + (range.empty() ? what : range));
  return x;
}

long long ConfigValue::integer(long long lo, long long hi, const std::string& what,
                               const std::string& range) const {
  long long x = 0;
  if (!impl_->node.IsScalar() || !YAML::convert<long long>::decode(impl_->node, x)) {
    fail("must be " + what);
  }
  if (x < lo || x > hi) fail("must be " + (range.empty() ? what : range));
  return x;
}

bool ConfigValue::boolean() const {
  bool x = false;
  if (!impl_->node.IsScalar() || !YAML::convert<bool>::decode(impl_->node, x)) {
    fail("must be true or false");
  }
  return x;
}

std::string ConfigValue::text(const std::string& what) const {
  if (!impl_->node.IsScalar()) fail("must be " + what);
  return impl_->node.Scalar();
}

std::vector<std::string> ConfigValue::strings() const {
  if (!impl_->node.IsSequence()) fail("must be a list of strings");
  std::vector<std::string> out;
  for (const YAML::Node& e : impl_->node) {
    const Impl item{impl_->loader, e, impl_->path};
    out.push_back(ConfigValue(&item).text("a string"));
  }
  return out;
}

void ConfigValue::section(const Table& table, const std::string& unknown, bool show_key) const {
  if (is_null()) return;
  if (!impl_->node.IsMap()) fail("must be a mapping");
  std::set<std::string> keys;
  for (const auto& kv : impl_->node) {
    const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : plain(kv.first);
    const Impl item{impl_->loader, kv.second, impl_->path + "." + key};
    const ConfigValue value(&item);
    if (!keys.insert(key).second) value.fail("key given twice");
    const auto it = table.find(key);
    if (it == table.end()) {
      std::string allowed;
      for (const auto& h : table) allowed += (allowed.empty() ? "" : ", ") + h.first;
      const Impl name{impl_->loader, show_key ? kv.first : kv.second, item.path};
      ConfigValue(&name).fail(unknown + " (expected one of: " + allowed + ")");
    }
    it->second(value);
  }
}

EngineConfig load_engine_config(const std::string& path, const ConfigValue::Table& extra) {
  const std::string text = read_file(path);
  return load_node(
      path, [&] { return single_document(text, path); }, &extra);
}

EngineConfig load_engine_config(const std::string& path) {
  const std::string text = read_file(path);
  return load_engine_config_from_string(text, path);
}

EngineConfig load_engine_config_from_string(const std::string& yaml, const std::string& name) {
  return load_node(name, [&] { return single_document(yaml, name); });
}

}  // namespace usvfdi::io
