// YAML configuration loader: defaults, shipped files, and every kind of error message.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/io/config.hpp"

namespace usvfdi::io {
namespace {

const std::string kSource = USV_FDI_SOURCE_DIR;

/// The ConfigError message of loading `yaml` as "cfg_test.yaml" (fails the test if none).
std::string error_of(const std::string& yaml) {
  try {
    load_engine_config_from_string(yaml, "cfg_test.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a ConfigError: " << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << yaml;
  return "";
}

#define EXPECT_MENTIONS(message, ...)                       \
  for (const char* part : {__VA_ARGS__}) {                  \
    EXPECT_NE((message).find(part), std::string::npos)      \
        << "message lacks '" << part << "': " << (message); \
  }

void expect_same(const EngineConfig& a, const EngineConfig& b) {
  EXPECT_EQ(a.B, b.B);
  EXPECT_EQ(a.identification_delay, b.identification_delay);
  const IdentificationParams &x = a.identification, &y = b.identification;
  EXPECT_EQ(x.method, y.method);
  EXPECT_EQ(x.eps1, y.eps1);
  EXPECT_EQ(x.eps2, y.eps2);
  EXPECT_EQ(x.gamma, y.gamma);
  EXPECT_EQ(x.normalised, y.normalised);
  EXPECT_EQ(x.mu, y.mu);
  EXPECT_EQ(x.lambda, y.lambda);
  EXPECT_EQ(x.warmup_time, y.warmup_time);
  EXPECT_EQ(x.max_gap, y.max_gap);
  EXPECT_EQ(x.curvature_correction, y.curvature_correction);
  EXPECT_EQ(x.cubic_correction, y.cubic_correction);
  EXPECT_EQ(x.instruments, y.instruments);
  EXPECT_EQ(x.max_std_error, y.max_std_error);
  EXPECT_EQ(x.guard, y.guard);
  EXPECT_EQ(x.guard_threshold, y.guard_threshold);
  EXPECT_EQ(x.guard_min_shift, y.guard_min_shift);
  EXPECT_EQ(x.guard_recent_time, y.guard_recent_time);
  EXPECT_EQ(x.uncertain_ratio, y.uncertain_ratio);
  EXPECT_EQ(x.uncertain_time, y.uncertain_time);
  EXPECT_EQ(x.a0, y.a0);
  EXPECT_EQ(x.min_excitation, y.min_excitation);
  EXPECT_EQ(x.settle_window, y.settle_window);
  EXPECT_EQ(x.settle_tolerance, y.settle_tolerance);
  EXPECT_EQ(x.settle_windows, y.settle_windows);
  EXPECT_EQ(x.settle_floor, y.settle_floor);
  EXPECT_EQ(a.speed.reference_speed, b.speed.reference_speed);
  EXPECT_EQ(a.speed.min_ratio, b.speed.min_ratio);
  EXPECT_EQ(a.speed.max_ratio, b.speed.max_ratio);
  EXPECT_EQ(a.speed.quantum, b.speed.quantum);
  EXPECT_EQ(a.speed.input_exponent, b.speed.input_exponent);
  const IsolationParams &p = a.isolation, &q = b.isolation;
  EXPECT_EQ(p.poles_v, q.poles_v);
  EXPECT_EQ(p.poles_g, q.poles_g);
  EXPECT_EQ(p.min_observability, q.min_observability);
  EXPECT_EQ(p.redesign_tolerance, q.redesign_tolerance);
  EXPECT_EQ(p.sigma_v, q.sigma_v);
  EXPECT_EQ(p.sigma_r, q.sigma_r);
  EXPECT_EQ(p.sigma_floor_v, q.sigma_floor_v);
  EXPECT_EQ(p.sigma_floor_r, q.sigma_floor_r);
  EXPECT_EQ(p.settle_time, q.settle_time);
  EXPECT_EQ(p.learn_time, q.learn_time);
  EXPECT_EQ(p.window, q.window);
  EXPECT_EQ(p.min_window_samples, q.min_window_samples);
  EXPECT_EQ(p.clip, q.clip);
  EXPECT_EQ(p.threshold, q.threshold);
  EXPECT_EQ(p.threshold_margin, q.threshold_margin);
  EXPECT_EQ(p.threshold_k, q.threshold_k);
  EXPECT_EQ(p.history_margin, q.history_margin);
  EXPECT_EQ(p.history, q.history);
  EXPECT_EQ(p.exit_ratio, q.exit_ratio);
  EXPECT_EQ(p.enter_time, q.enter_time);
  EXPECT_EQ(p.young_enter_ratio, q.young_enter_ratio);
  EXPECT_EQ(p.onset_lookback, q.onset_lookback);
  EXPECT_EQ(p.close_capped_bars, q.close_capped_bars);
  EXPECT_EQ(p.relearn_after_raise, q.relearn_after_raise);
  EXPECT_EQ(p.on_lost_convergence, q.on_lost_convergence);
  EXPECT_EQ(p.leave_time, q.leave_time);
  EXPECT_EQ(p.second_fault_time, q.second_fault_time);
  EXPECT_EQ(p.mismatch_window, q.mismatch_window);
  EXPECT_EQ(p.resume_after_fault, q.resume_after_fault);
  EXPECT_EQ(p.min_active_time, q.min_active_time);
  EXPECT_EQ(p.c_min, q.c_min);
  EXPECT_EQ(p.c_margin, q.c_margin);
  EXPECT_EQ(p.resume_time, q.resume_time);
  EXPECT_EQ(p.stale_timeout, q.stale_timeout);
  EXPECT_EQ(p.stuck_time, q.stuck_time);
  EXPECT_EQ(p.stuck_min_samples, q.stuck_min_samples);
  EXPECT_EQ(p.max_abs_v, q.max_abs_v);
  EXPECT_EQ(p.max_abs_r, q.max_abs_r);
  EXPECT_EQ(p.max_abs_delta, q.max_abs_delta);
  EXPECT_EQ(p.spike_gate, q.spike_gate);
  const JumpParams &j = p.jump, &k = q.jump;
  EXPECT_EQ(j.enabled, k.enabled);
  EXPECT_EQ(j.pre_window, k.pre_window);
  EXPECT_EQ(j.post_window, k.post_window);
  EXPECT_EQ(j.min_samples, k.min_samples);
  EXPECT_EQ(j.persist_samples, k.persist_samples);
  EXPECT_EQ(j.persist_time, k.persist_time);
  EXPECT_EQ(j.threshold, k.threshold);
  EXPECT_EQ(j.noise_threshold, k.noise_threshold);
  EXPECT_EQ(j.margin, k.margin);
  EXPECT_EQ(j.noise_window, k.noise_window);
  EXPECT_EQ(j.noise_min_samples, k.noise_min_samples);
  EXPECT_EQ(j.learn_time, k.learn_time);
  EXPECT_EQ(j.history, k.history);
  EXPECT_EQ(j.scale_time, k.scale_time);
  EXPECT_EQ(j.leave_time, k.leave_time);
  EXPECT_EQ(j.exit_ratio, k.exit_ratio);
  EXPECT_EQ(j.hold_max, k.hold_max);
  EXPECT_EQ(j.max_gap, k.max_gap);
  EXPECT_EQ(j.b_uncertainty, k.b_uncertainty);
  EXPECT_EQ(j.rudder_lag, k.rudder_lag);
  EXPECT_EQ(j.bend_margin, k.bend_margin);
  EXPECT_EQ(j.bend_rate, k.bend_rate);
  EXPECT_EQ(p.spike_window, q.spike_window);
  EXPECT_EQ(p.spike_count, q.spike_count);
  EXPECT_EQ(p.invalid_count, q.invalid_count);
  EXPECT_EQ(p.classify_window, q.classify_window);
  EXPECT_EQ(p.drift_check, q.drift_check);
  EXPECT_EQ(p.drift_k, q.drift_k);
  EXPECT_EQ(p.drift_threshold, q.drift_threshold);
  EXPECT_EQ(p.drift_lag, q.drift_lag);
  EXPECT_EQ(p.drift_min_history, q.drift_min_history);
}

TEST(Config, OnlyModelBGivesTheCoreDefaults) {
  const EngineConfig c = load_engine_config_from_string("model:\n  B: [0.5, -2]\n");
  EngineConfig want;
  want.B = Vec2(0.5, -2.0);
  expect_same(c, want);
}

TEST(Config, DefaultYamlStatesExactlyTheCoreDefaults) {
  // config/default.yaml documents every key with its default: it must not drift.
  const EngineConfig c = load_engine_config(kSource + "/config/default.yaml");
  EngineConfig want;
  want.B = c.B;
  expect_same(c, want);
}

TEST(Config, ShippedVesselConfigsMatchTheVesselModels) {
  for (const VesselModel& v : shipped_vessels()) {
    SCOPED_TRACE(v.name);
    const EngineConfig c = load_engine_config(kSource + "/config/vessels/" + v.name + ".yaml");
    EXPECT_EQ(c.B, v.B);
    EXPECT_EQ(c.isolation.sigma_v, v.sigma_v);
    EXPECT_EQ(c.isolation.sigma_r, v.sigma_r);
  }
}

TEST(Config, PaperYamlSelectsThePapersEstimator) {
  const EngineConfig c = load_engine_config(kSource + "/config/paper.yaml");
  EXPECT_FALSE(c.isolation.jump.enabled);  // the paper detects with its observers alone
  EXPECT_EQ(c.identification.method, IdentMethod::kPaper);
  EXPECT_EQ(c.identification.eps1, 100.0);
  EXPECT_EQ(c.identification.eps2, 200.0);
  EXPECT_EQ(c.identification.gamma, 1.0);
  EXPECT_FALSE(c.identification.normalised);
}

TEST(Config, EveryKeyIsRead) {
  const EngineConfig c = load_engine_config_from_string(R"(
model: {B: [1, 2], A0: [-1, -2, -3, -4]}
identification:
  method: paper
  eps1: 3
  eps2: 4
  gamma: 5
  normalised: false
  mu: 1e-10
  lambda: 0.2
  warmup_time: 7
  max_gap: 2
  curvature_correction: false
  cubic_correction: false
  instruments: regressor
  max_std_error: 0.2
  precision: coefficients
  max_prediction_error: 0.03
  uncertain_ratio: 4
  uncertain_time: 20
  guard: false
  guard_threshold: 50
  guard_min_shift: 0.002
  guard_recent_time: 90
  min_excitation: 0.5
  settle_window: 2
  settle_tolerance: 0.02
  settle_windows: 4
  settle_floor: 0.001
  delay: 0.25
isolation:
  poles_v: [-1, -2]
  poles_g: [-3, -4]
  sigma_v: 0.01
  sigma_r: 0.001
  stuck_min_samples: 7
  stuck_probability: 1e-6
  stuck_learn_time: 30
  stuck_time_max: 4
  spike_count: 5
  classify_window: 9
  drift_check: true
  drift_k: 0.25
  drift_threshold: 7
  drift_lag: 30
  drift_min_history: 90
  history_margin: 2.5
  history: 1200
  second_fault_time: 3.5
  young_enter_ratio: 1.25
  onset_lookback: 2.5
  close_capped_bars: false
  relearn_after_raise: false
  resume_after_fault: 4.5
jump:
  enabled: false
  pre_window: 2
  persist_time: 0.2
  margin: 3
  hold_max: 45
  rudder_lag: 0.1
  bend_margin: 0.5
  bend_rate: 3
service:
  domain_id: 7
  mmsi: 257000000
  topics: {ins: usv/ins, rudder: usv/rudder}
  partitions: [fleet]
)");
  EXPECT_EQ(c.identification.a0, Vec4(-1, -2, -3, -4));
  EXPECT_EQ(c.identification.method, IdentMethod::kPaper);
  EXPECT_EQ(c.identification.eps2, 4.0);
  EXPECT_EQ(c.identification.mu, 1e-10);
  EXPECT_FALSE(c.identification.curvature_correction);
  EXPECT_EQ(c.identification.settle_windows, 4);
  EXPECT_EQ(c.identification_delay, 0.25);
  EXPECT_EQ(c.isolation.poles_g, Vec2(-3, -4));
  EXPECT_EQ(c.isolation.stuck_min_samples, 7);
  EXPECT_EQ(c.isolation.classify_window, 9.0);
  EXPECT_TRUE(c.isolation.drift_check);
  EXPECT_EQ(c.isolation.drift_k, 0.25);
  EXPECT_EQ(c.isolation.drift_threshold, 7.0);
  EXPECT_EQ(c.isolation.drift_lag, 30.0);
  EXPECT_EQ(c.isolation.drift_min_history, 90.0);
  EXPECT_EQ(c.isolation.history_margin, 2.5);
  EXPECT_EQ(c.isolation.history, 1200.0);
  EXPECT_FALSE(c.identification.cubic_correction);
  EXPECT_EQ(c.identification.instruments, Instruments::kRegressor);
  EXPECT_EQ(c.identification.max_std_error, 0.2);
  EXPECT_EQ(c.identification.precision, Precision::kCoefficients);
  EXPECT_EQ(c.identification.max_prediction_error, 0.03);
  EXPECT_EQ(c.identification.uncertain_ratio, 4.0);
  EXPECT_EQ(c.identification.uncertain_time, 20.0);
  EXPECT_EQ(c.isolation.stuck_probability, 1e-6);
  EXPECT_EQ(c.isolation.stuck_learn_time, 30.0);
  EXPECT_EQ(c.isolation.stuck_time_max, 4.0);
  EXPECT_FALSE(c.identification.guard);
  EXPECT_EQ(c.identification.guard_threshold, 50.0);
  EXPECT_EQ(c.identification.guard_min_shift, 0.002);
  EXPECT_EQ(c.identification.guard_recent_time, 90.0);
  EXPECT_EQ(c.isolation.second_fault_time, 3.5);
  EXPECT_EQ(c.isolation.young_enter_ratio, 1.25);
  EXPECT_EQ(c.isolation.onset_lookback, 2.5);
  EXPECT_FALSE(c.isolation.close_capped_bars);
  EXPECT_FALSE(c.isolation.relearn_after_raise);
  EXPECT_EQ(c.isolation.resume_after_fault, 4.5);
  EXPECT_FALSE(c.isolation.jump.enabled);
  EXPECT_EQ(c.isolation.jump.pre_window, 2.0);
  EXPECT_EQ(c.isolation.jump.persist_time, 0.2);
  EXPECT_EQ(c.isolation.jump.margin, 3.0);
  EXPECT_EQ(c.isolation.jump.hold_max, 45.0);
  EXPECT_EQ(c.isolation.jump.rudder_lag, 0.1);
  EXPECT_EQ(c.isolation.jump.bend_margin, 0.5);
  EXPECT_EQ(c.isolation.jump.bend_rate, 3.0);
}

TEST(ConfigError, AJumpCheckKeyOutOfItsRangeIsNamed) {
  const std::string m =
      error_of("model:\n  B: [1, 2]\njump:\n  post_window: 0.5\n  persist_time: 0.8\n");
  EXPECT_MENTIONS(m, "jump.persist_time", "0.8", "post_window");
}

TEST(ConfigError, UnknownKeyNamesFileKeyLineAndValue) {
  const std::string m = error_of("model:\n  B: [1, 2]\nisolation:\n  polesv: [-1, -2]\n");
  EXPECT_MENTIONS(m, "cfg_test.yaml:4", "isolation.polesv", "[-1, -2]", "unknown key");
}

TEST(ConfigError, UnknownTopLevelKey) {
  const std::string m = error_of("model:\n  B: [1, 2]\nisolaton:\n  window: 1\n");
  EXPECT_MENTIONS(m, "cfg_test.yaml:4", "isolaton", "unknown key");
}

TEST(ConfigError, WrongTypeNamesFileKeyLineAndValue) {
  const std::string m = error_of("model:\n  B: [1, 2]\nidentification:\n  eps1: fast\n");
  EXPECT_MENTIONS(m, "cfg_test.yaml:4", "identification.eps1", "'fast'", "number");
  const std::string n = error_of("model:\n  B: [1, 2]\nisolation:\n  spike_count: 2.5\n");
  EXPECT_MENTIONS(n, "cfg_test.yaml:4", "isolation.spike_count", "2.5", "integer");
  const std::string b = error_of("model:\n  B: [1, 2]\nidentification:\n  normalised: 3\n");
  EXPECT_MENTIONS(b, "cfg_test.yaml:4", "identification.normalised", "3");
  const std::string s = error_of("model:\n  B: [1, 2]\nisolation: 5\n");
  EXPECT_MENTIONS(s, "cfg_test.yaml:3", "isolation", "'5'", "mapping");
  const std::string e = error_of("model:\n  B: [1, x]\n");
  EXPECT_MENTIONS(e, "cfg_test.yaml:2", "model.B[1]", "'x'");
  const std::string c = error_of("model:\n  B: [1, 2]\nidentification:\n  precision: fine\n");
  EXPECT_MENTIONS(c, "cfg_test.yaml:4", "identification.precision", "'fine'",
                  "expected coefficients or prediction");
}

TEST(ConfigError, WrongListLengthNamesFileKeyLineAndValue) {
  const std::string m = error_of("model:\n  B: [1, 2]\nisolation:\n  poles_v: [-1, -2, -3]\n");
  EXPECT_MENTIONS(m, "cfg_test.yaml:4", "isolation.poles_v", "[-1, -2, -3]", "2 numbers");
  const std::string a = error_of("model:\n  B: [1, 2]\n  A0: [1, 2]\n");
  EXPECT_MENTIONS(a, "cfg_test.yaml:3", "model.A0", "[1, 2]", "4 numbers");
  const std::string s = error_of("model:\n  B: 3\n");
  EXPECT_MENTIONS(s, "cfg_test.yaml:2", "model.B", "'3'");
}

TEST(ConfigError, MissingModelB) {
  const std::string m = error_of("identification:\n  eps1: 2\n");
  EXPECT_MENTIONS(m, "cfg_test.yaml", "model.B", "required");
  EXPECT_MENTIONS(error_of(""), "cfg_test.yaml", "model.B", "required");
}

TEST(ConfigError, MissingFileNamesTheFile) {
  try {
    load_engine_config("/nonexistent/dir/engine.yaml");
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/engine.yaml"), std::string::npos)
        << e.what();
  }
}

TEST(ConfigError, SyntaxErrorNamesFileAndLine) {
  const std::string m = error_of("model:\n  B: [1, 2\nisolation:\n  window: 1\n");
  EXPECT_MENTIONS(m, "cfg_test.yaml:", "syntax");
  const std::string n = error_of("model:\n  B: [1, 2]\n   bad_indent: 1\n  - x\n");
  EXPECT_MENTIONS(n, "cfg_test.yaml:");
}

TEST(ConfigError, ValidateFailureIsRethrownWithFileKeyLineAndValue) {
  const std::string m = error_of("model:\n  B: [1, 2]\nidentification:\n  eps1: -3\n");
  EXPECT_MENTIONS(m, "cfg_test.yaml:4", "identification.eps1", "-3", "positive");
  const std::string b = error_of("# B must not vanish\nmodel:\n  B: [0, 0]\n");
  EXPECT_MENTIONS(b, "cfg_test.yaml:3", "model.B", "[0, 0]");
  const std::string p = error_of("model:\n  B: [1, 2]\nisolation:\n  poles_g: [-1, 0.5]\n");
  EXPECT_MENTIONS(p, "cfg_test.yaml:4", "isolation.poles_g", "[-1, 0.5]", "negative");
  const std::string d = error_of("model:\n  B: [1, 2]\nidentification:\n  delay: -1\n");
  EXPECT_MENTIONS(d, "cfg_test.yaml:4", "identification.delay", "-1");
  const std::string a = error_of("model:\n  B: [1, 2]\n  A0: [1, 2, 3, .nan]\n");
  EXPECT_MENTIONS(a, "cfg_test.yaml:3", "model.A0", ".nan");
}

TEST(ConfigError, ValuesThatSwitchDetectionOffAreRefusedWithTheirRange) {
  const std::string d = error_of("model:\n  B: [1, 2]\nidentification:\n  delay: 1e9\n");
  EXPECT_MENTIONS(d, "cfg_test.yaml:4", "identification.delay", "1e9", "allowed range",
                  "[0, 60] s");
  const std::string t = error_of("model:\n  B: [1, 2]\nisolation:\n  threshold: .inf\n");
  EXPECT_MENTIONS(t, "cfg_test.yaml:4", "isolation.threshold", ".inf", "finite", "[0, 1000]");
  const std::string b = error_of("model:\n  B: [1e300, -2]\n");
  EXPECT_MENTIONS(b, "cfg_test.yaml:2", "model.B[0]", "1e300", "[-1000, 1000]");
  const std::string n = error_of("model:\n  B: [1, 2]\nisolation:\n  window: .nan\n");
  EXPECT_MENTIONS(n, "cfg_test.yaml:4", "isolation.window", "finite");
  const std::string c = error_of("model:\n  B: [1, 2]\nisolation:\n  spike_count: 100000000\n");
  EXPECT_MENTIONS(c, "cfg_test.yaml:4", "isolation.spike_count", "[1, 1e+06]");
  // the engine's own rules keep their messages
  const std::string e = error_of("model:\n  B: [1, 2]\nidentification:\n  eps1: -3\n");
  EXPECT_MENTIONS(e, "positive");
}

TEST(ConfigError, ShippedConfigsAreWithinTheRanges) {
  for (const char* f : {"default.yaml", "paper.yaml", "vessels/otter.yaml", "vessels/mariner.yaml",
                        "scenarios/paper.yaml", "service/example.yaml"}) {
    EXPECT_NO_THROW(load_engine_config(kSource + "/config/" + f)) << f;
  }
}

TEST(ConfigError, ASecondDocumentIsRefused) {
  const std::string m = error_of("model:\n  B: [1, 2]\n---\nmodel:\n  B: [3, 4]\n");
  EXPECT_MENTIONS(m, "cfg_test.yaml:", "second YAML document");
  EXPECT_NO_THROW(load_engine_config_from_string("---\nmodel:\n  B: [1, 2]\n...\n"));
}

TEST(ConfigError, DuplicateKey) {
  const std::string m = error_of("model:\n  B: [1, 2]\n  B: [3, 4]\n");
  EXPECT_MENTIONS(m, "cfg_test.yaml:3", "model.B", "twice");
}

TEST(ConfigError, ServiceSectionMustBeAMapping) {
  EXPECT_NO_THROW(load_engine_config_from_string("model: {B: [1, 2]}\nservice:\n  anything: 1\n"));
  EXPECT_NO_THROW(load_engine_config_from_string("model: {B: [1, 2]}\nservice:\n"));
  const std::string m = error_of("model: {B: [1, 2]}\nservice: [1, 2]\n");
  EXPECT_MENTIONS(m, "cfg_test.yaml:2", "service", "mapping");
}

TEST(ConfigError, FileErrorsNameThePath) {
  const std::string path = ::testing::TempDir() + "usv_fdi_cfg_error.yaml";
  {
    std::ofstream f(path);
    f << "model:\n  B: [1, 2]\nisolation:\n  window: soon\n";
  }
  try {
    load_engine_config(path);
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    const std::string where = path + ":4";
    EXPECT_MENTIONS(m, where.c_str(), "isolation.window", "soon");
  }
}

}  // namespace
}  // namespace usvfdi::io
