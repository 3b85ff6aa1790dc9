// The benchmark's data: fault injection on recorded samples, the standard fault set, and the
// HSVA KVLCC2 tests and their model (B from the data's kvlcc2_model.yaml through the engine's
// config loader) read from shared/realdata beside the repository (skipped, saying why, where
// they are missing).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>
#include <string>

#include "runner.hpp"
#include "usv_fdi/io/config.hpp"

namespace usvfdi::bench {
namespace {

std::vector<Sample> ramp(int n, double dt) {
  std::vector<Sample> x;
  for (int k = 0; k < n; ++k) x.push_back(Sample{k * dt, 0.01 * k, -0.001 * k, 0.0});
  return x;
}

TEST(BenchData, StandardFaultsAreTheIssuesSet) {
  const auto f = standard_faults(0.002);
  ASSERT_EQ(f.size(), 5u);
  EXPECT_EQ(f[0].kind, FaultKind::kBias);
  EXPECT_NEAR(f[0].magnitude, 0.02, 1e-15);
  EXPECT_EQ(f[1].kind, FaultKind::kStuck);
  EXPECT_EQ(f[2].kind, FaultKind::kDrift);
  EXPECT_NEAR(f[2].magnitude * 30.0, 0.02, 1e-15);  // 10 sigma per 30 s
  EXPECT_EQ(f[3].kind, FaultKind::kNoise);
  // Noise x8: the extra noise makes the total std 8 sigma.
  EXPECT_NEAR(std::hypot(0.002, f[3].magnitude), 8 * 0.002, 1e-12);
  EXPECT_EQ(f[4].kind, FaultKind::kScale);
  EXPECT_EQ(f[4].magnitude, 0.5);
}

TEST(BenchData, FaultsChangeOnlyTheirChannelInsideTheirWindow) {
  const auto clean = ramp(100, 0.1);  // t = 0 .. 9.9
  auto x = clean;
  apply_fault(&x, {Sensor::kGyro, FaultKind::kBias, 2.0, 5.0}, 0.5, 1);
  for (std::size_t k = 0; k < x.size(); ++k) {
    EXPECT_EQ(x[k].v, clean[k].v);
    const bool in = clean[k].t >= 2.0 && clean[k].t < 5.0;
    EXPECT_NEAR(x[k].r, clean[k].r + (in ? 0.5 : 0.0), 1e-15) << k;
  }
  x = clean;
  apply_fault(&x, {Sensor::kAccelerometer, FaultKind::kStuck, 2.0, 5.0}, 0.0, 1);
  for (std::size_t k = 0; k < x.size(); ++k) {
    const bool in = clean[k].t >= 2.0 && clean[k].t < 5.0;
    EXPECT_EQ(x[k].v, in ? clean[20].v : clean[k].v) << k;
    EXPECT_EQ(x[k].r, clean[k].r);
  }
  x = clean;
  apply_fault(&x, {Sensor::kAccelerometer, FaultKind::kDrift, 2.0, 5.0}, 0.1, 1);
  EXPECT_NEAR(x[40].v - clean[40].v, 0.1 * (4.0 - 2.0), 1e-12);
  EXPECT_EQ(x[50].v, clean[50].v);
  x = clean;
  apply_fault(&x, {Sensor::kAccelerometer, FaultKind::kScale, 2.0, 5.0}, 0.5, 1);
  EXPECT_NEAR(x[30].v, 1.5 * clean[30].v, 1e-15);
  auto a = clean, b = clean;
  apply_fault(&a, {Sensor::kGyro, FaultKind::kNoise, 0.0, 10.0}, 0.1, 7);
  apply_fault(&b, {Sensor::kGyro, FaultKind::kNoise, 0.0, 10.0}, 0.1, 7);
  double ss = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].r, b[k].r);  // deterministic by seed
    ss += (a[k].r - clean[k].r) * (a[k].r - clean[k].r);
  }
  EXPECT_NEAR(std::sqrt(ss / a.size()), 0.1, 0.03);
  EXPECT_THROW(apply_fault(&x, {Sensor::kGyro, FaultKind::kSpikes, 0, 1}, 1, 1),
               std::invalid_argument);
}

TEST(BenchData, ConcatenationKeepsTimeIncreasingWithTheGap) {
  std::vector<RecordedRun> runs(2);
  runs[0].samples = ramp(10, 0.05);
  runs[1].samples = ramp(5, 0.05);
  for (Sample& s : runs[1].samples) s.t += 100.0;  // its own clock
  std::vector<double> starts;
  const auto all = concatenate(runs, 3.0, &starts);
  ASSERT_EQ(all.size(), 15u);
  ASSERT_EQ(starts.size(), 2u);
  EXPECT_EQ(starts[0], 0.0);
  EXPECT_NEAR(starts[1], 0.45 + 3.0, 1e-12);
  EXPECT_NEAR(all[10].t, 3.45, 1e-12);
  for (std::size_t k = 1; k < all.size(); ++k) EXPECT_GT(all[k].t, all[k - 1].t);
}

TEST(BenchData, RecordedNoiseOfWhiteNoiseIsItsSigma) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  RecordedRun run;
  for (int k = 0; k < 20000; ++k) {
    const double t = 0.05 * k;
    run.samples.push_back(Sample{t, 0.1 * std::sin(0.1 * t) + 0.002 * n(rng),
                                 0.01 * std::cos(0.1 * t) + 0.0003 * n(rng), 0.0});
  }
  const Vec2 s = recorded_noise({run});
  EXPECT_NEAR(s(0), 0.002, 0.0001);
  EXPECT_NEAR(s(1), 0.0003, 0.000015);
}

class RealData : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    dir_ = find_realdata(USV_FDI_SOURCE_DIR, &why);
    if (dir_.empty()) GTEST_SKIP() << why;
  }
  std::string dir_;
};

TEST_F(RealData, ThirteenRunsAt20HzOneAfterAnother) {
  const auto runs = load_hsva(dir_);
  ASSERT_EQ(runs.size(), 13u);
  double total = 0;
  for (const RecordedRun& r : runs) {
    const double len = r.samples.back().t - r.samples.front().t;
    EXPECT_GE(len, 65.0) << r.name;
    EXPECT_LE(len, 211.0) << r.name;
    EXPECT_NEAR(len / (r.samples.size() - 1), 0.05, 1e-6) << r.name;
    total += len;
  }
  std::vector<double> starts;
  const auto all = concatenate(runs, 3.0, &starts);
  EXPECT_NEAR(all.back().t, total + 12 * 3.0, 1e-6);
  for (std::size_t k = 1; k < all.size(); ++k) ASSERT_GT(all[k].t, all[k - 1].t) << k;
  // The healthy noise: positive, and well below the motion (|r| reaches ~0.02 rad/s).
  const Vec2 sigma = recorded_noise(runs);
  EXPECT_GT(sigma(0), 0.0);
  EXPECT_GT(sigma(1), 0.0);
  EXPECT_LT(sigma(0), 0.005);
  EXPECT_LT(sigma(1), 0.002);
}

/// The whole text of a file ("" if unreadable).
std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Every number in text, in order (U+2212 minus signs read as '-').
std::vector<double> numbers_in(std::string text) {
  for (std::size_t p; (p = text.find("\xE2\x88\x92")) != std::string::npos;) {
    text.replace(p, 3, "-");
  }
  std::vector<double> out;
  const std::regex num(R"([-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), num); it != std::sregex_iterator();
       ++it) {
    out.push_back(std::stod(it->str()));
  }
  return out;
}

TEST_F(RealData, HsvaModelTakesBFromTheYamlAsAUserWouldAndAFromTheReadme) {
  const std::string yaml = dir_ + "/kvlcc2_model.yaml";
  const HsvaModel m = load_hsva_model(dir_);
  // B: the two numbers of the yaml's `B: [b1, b2]` line, exactly (no copy of them in the
  // bench code), and what a user's `usv-fdi replay --config` of that file gets.
  std::istringstream lines(slurp(yaml));
  std::vector<double> b;
  for (std::string line; std::getline(lines, line);) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    if (line.find("B:") != std::string::npos) b = numbers_in(line.substr(line.find("B:") + 2));
  }
  ASSERT_EQ(b.size(), 2u) << yaml << ": no `B: [b1, b2]` line";
  EXPECT_EQ(m.B(0), b[0]);
  EXPECT_EQ(m.B(1), b[1]);
  const EngineConfig user = io::load_engine_config(yaml);
  EXPECT_EQ(m.B, user.B);
  // delta + to port in the data: b1 > 0, b2 < 0 (README, "Signs").
  EXPECT_GT(m.B(0), 0.0);
  EXPECT_LT(m.B(1), 0.0);
  // A_ref: the README's "A ~ [[a11, a12], [a21, a22]]" of the same linearisation.
  const std::string readme = slurp(dir_ + "/README.md");
  const auto at = readme.find("A \xE2\x89\x88 [[");
  ASSERT_NE(at, std::string::npos) << dir_ << "/README.md: no 'A \xE2\x89\x88 [[' found";
  const std::string text = readme.substr(at + 5, readme.find("]]", at) - at - 5);
  const std::vector<double> a = numbers_in(text);
  ASSERT_EQ(a.size(), 4u) << text;
  EXPECT_EQ(m.A_ref(0, 0), a[0]);
  EXPECT_EQ(m.A_ref(0, 1), a[1]);
  EXPECT_EQ(m.A_ref(1, 0), a[2]);
  EXPECT_EQ(m.A_ref(1, 1), a[3]);
}

/// A fresh empty directory under the system's temporary directory, removed on destruction.
class TempDir {
 public:
  TempDir() {
    path_ = std::filesystem::temp_directory_path() /
            ("usv_fdi_hsva_model_" + std::to_string(::getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string str() const { return path_.string(); }
  void write(const std::string& name, const std::string& text) const {
    std::ofstream(path_ / name) << text;
  }

 private:
  std::filesystem::path path_;
};

/// The message of the io::ConfigError that f throws ("" and a failure if it throws none).
template <class F>
std::string config_error(F f) {
  try {
    f();
  } catch (const io::ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no io::ConfigError";
  return "";
}

TEST(BenchData, HsvaModelRefusesAMissingOrBadYamlNamingTheFile) {
  const TempDir dir;
  const std::string file = dir.str() + "/kvlcc2_model.yaml";
  // missing
  std::string why = config_error([&] { load_hsva_model(dir.str()); });
  EXPECT_NE(why.find(file), std::string::npos) << why;
  EXPECT_NE(why.find("cannot read"), std::string::npos) << why;
  // B with one element
  dir.write("kvlcc2_model.yaml", "model:\n  B: [0.0345]\n");
  why = config_error([&] { load_hsva_model(dir.str()); });
  EXPECT_NE(why.find(file), std::string::npos) << why;
  EXPECT_NE(why.find("model.B"), std::string::npos) << why;
  // no model.B
  dir.write("kvlcc2_model.yaml", "model:\n  reference_speed: 1.179\n");
  why = config_error([&] { load_hsva_model(dir.str()); });
  EXPECT_NE(why.find(file), std::string::npos) << why;
  EXPECT_NE(why.find("model.B"), std::string::npos) << why;
  // not YAML
  dir.write("kvlcc2_model.yaml", "model: [B: {\n");
  why = config_error([&] { load_hsva_model(dir.str()); });
  EXPECT_NE(why.find(file), std::string::npos) << why;
  // and a good one is read
  dir.write("kvlcc2_model.yaml", "model:\n  B: [0.5, -0.25]\n");
  EXPECT_EQ(load_hsva_model(dir.str()).B, Vec2(0.5, -0.25));
}

}  // namespace
}  // namespace usvfdi::bench
