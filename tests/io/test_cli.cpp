// End-to-end tests of the usv-fdi executable: sim -> CSV -> replay -> JSON Lines, exit
// codes and messages on bad input.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "json_lite.hpp"
#include "support/run_cli.hpp"

namespace usvfdi::io {
namespace {

namespace js = usvfdi::testing_json;
using testing_cli::kExe;
using testing_cli::kSource;
using testing_cli::Outcome;
using testing_cli::slurp;

void spit(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
}

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = ::testing::TempDir() + "usv_fdi_cli_" + info->name() + "_" + std::to_string(::getpid()) +
           "/";
    ASSERT_EQ(std::system(("mkdir -p '" + dir_ + "'").c_str()), 0);
  }
  void TearDown() override {
    if (!HasFailure()) std::system(("rm -rf '" + dir_ + "'").c_str());
  }

  std::string path(const std::string& name) const { return dir_ + name; }

  /// Runs `usv-fdi ARGS`, after the shell commands `prefix` (e.g. "ulimit -f 4; ").
  Outcome run(const std::string& args, const std::string& prefix = "") const {
    return shell(prefix + "'" + kExe + "' " + args);
  }

  /// Runs shell commands, collecting their exit code, stdout and stderr.
  Outcome shell(const std::string& commands) const {
    return testing_cli::run_shell(commands, dir_);
  }

  /// A short simulated CSV (paper scenario on the Otter, 10 Hz, 30 s).
  std::string small_csv() const {
    const std::string csv = path("small.csv");
    const Outcome r =
        run("sim --vessel otter --scenario paper --rate 10 --duration 30 --output '" + csv + "'");
    EXPECT_EQ(r.code, 0) << r.err;
    return csv;
  }

  std::string dir_;
};

std::vector<js::Value> parse_lines(const std::string& text) {
  std::vector<js::Value> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    EXPECT_FALSE(line.empty());
    out.push_back(js::parse(line));  // throws on anything that is not one JSON value
    EXPECT_EQ(out.back().kind, js::Value::kObject) << line;
  }
  return out;
}

bool has(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST_F(Cli, SimThenReplayWritesWellFormedRecords) {
  const std::string csv = small_csv();
  const std::string text = slurp(csv);
  EXPECT_EQ(text.rfind("t,v,r,delta,v_true,r_true,delta_true,psi,psi_ref,fault_a,fault_g\n", 0),
            0u);
  EXPECT_TRUE(has(text, ",bias\n")) << "the gyro bias of the paper scenario from t = 20 s";

  const std::string cfg = kSource + "/config/vessels/otter.yaml";
  // to a file
  const std::string jsonl = path("out.jsonl");
  Outcome r = run("replay --config '" + cfg + "' --input '" + csv + "' --output '" + jsonl + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto recs = parse_lines(slurp(jsonl));
  // and to stdout: the same bytes
  Outcome s = run("replay --config '" + cfg + "' --input '" + csv + "'");
  ASSERT_EQ(s.code, 0) << s.err;
  EXPECT_EQ(s.out, slurp(jsonl));

  ASSERT_GE(recs.size(), 31u);  // >= one estimate per second of data, plus the summary
  int estimates = 0;
  for (const js::Value& v : recs) {
    const std::string type = v.at("type").str;
    if (type == "estimate") {
      ++estimates;
      EXPECT_EQ(v.at("a").arr.size(), 4u);
      EXPECT_EQ(v.at("converged").kind, js::Value::kBool);
    } else if (type == "event") {
      for (const char* k :
           {"stamp", "sensor", "state", "kind", "sequence", "incarnation", "c_a", "c_g",
            "statistic", "threshold", "onset_time", "detection_time", "a", "message"}) {
        EXPECT_TRUE(v.has(k)) << k;
      }
    } else {
      EXPECT_EQ(type, "summary");
    }
  }
  EXPECT_GE(estimates, 30);
  const js::Value& sum = recs.back();
  EXPECT_EQ(sum.at("type").str, "summary");
  EXPECT_EQ(sum.at("samples").num, 301.0);
  EXPECT_EQ(sum.at("duration_s").num, 30.0);
  EXPECT_TRUE(sum.at("complete").b);
}

TEST_F(Cli, ConfigErrorsExitWith2AndNameFileKeyAndValue) {
  const std::string csv = small_csv();
  Outcome r = run("replay --config '" + path("missing.yaml") + "' --input '" + csv + "'");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "missing.yaml")) << r.err;
  EXPECT_TRUE(r.out.empty());

  spit(path("bad.yaml"), "model:\n  B: [1, 2]\nisolation:\n  poles_v: [-1, -2, -3]\n");
  r = run("replay --config '" + path("bad.yaml") + "' --input '" + csv + "'");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(has(r.err, "bad.yaml:4")) << r.err;
  EXPECT_TRUE(has(r.err, "isolation.poles_v")) << r.err;
  EXPECT_TRUE(has(r.err, "[-1, -2, -3]")) << r.err;
}

TEST_F(Cli, InputErrorsExitWith3AndKeepTheRecordsBefore) {
  const std::string cfg = kSource + "/config/vessels/otter.yaml";
  Outcome r = run("replay --config '" + cfg + "' --input '" + path("none.csv") + "'");
  EXPECT_EQ(r.code, 3);
  EXPECT_TRUE(has(r.err, "none.csv")) << r.err;

  spit(path("nocol.csv"), "t,v,r\n0,0,0\n");
  r = run("replay --config '" + cfg + "' --input '" + path("nocol.csv") + "'");
  EXPECT_EQ(r.code, 3);
  EXPECT_TRUE(has(r.err, "nocol.csv:1")) << r.err;
  EXPECT_TRUE(has(r.err, "'delta'")) << r.err;

  // A bad number on line 203 (t = 20.1 s) of an otherwise good file.
  std::istringstream in(slurp(small_csv()));
  std::string line, text;
  for (int n = 1; std::getline(in, line); ++n)
    text += (n == 203 ? "20.1,0.01,1.2.3,0,0,0,0,0,0,," : line) + "\n";
  spit(path("bad.csv"), text);
  const std::string jsonl = path("bad.jsonl");
  r = run("replay --config '" + cfg + "' --input '" + path("bad.csv") + "' --output '" + jsonl +
          "'");
  EXPECT_EQ(r.code, 3);
  EXPECT_TRUE(has(r.err, "bad.csv:203")) << r.err;
  EXPECT_TRUE(has(r.err, "'r'")) << r.err;
  EXPECT_TRUE(has(r.err, "1.2.3")) << r.err;
  const auto recs = parse_lines(slurp(jsonl));
  ASSERT_GE(recs.size(), 20u);  // the estimates of the first 20 s are there
  EXPECT_EQ(recs.back().at("type").str, "summary");
  EXPECT_FALSE(recs.back().at("complete").b);
  EXPECT_EQ(recs.back().at("samples").num, 201.0);
  EXPECT_TRUE(has(recs.back().at("error").str, "bad.csv:203"));
}

TEST_F(Cli, ReplayRefusesAnOutputThatIsItsInputOrConfig) {
  const std::string csv = small_csv();
  const std::string recording = slurp(csv);
  spit(path("cfg.yaml"), slurp(kSource + "/config/vessels/otter.yaml"));
  const std::string cfg = path("cfg.yaml");
  const std::string settings = slurp(cfg);
  ASSERT_EQ(::symlink(csv.c_str(), path("link.csv").c_str()), 0);
  ASSERT_EQ(::link(csv.c_str(), path("hard.csv").c_str()), 0);
  ASSERT_EQ(::symlink(cfg.c_str(), path("link.yaml").c_str()), 0);
  ASSERT_EQ(std::system(("mkdir -p '" + path("sub") + "'").c_str()), 0);
  for (const std::string& out : {csv, cfg, path("link.csv"), path("hard.csv"), path("link.yaml"),
                                 path("sub/../small.csv")}) {
    const Outcome r =
        run("replay --config '" + cfg + "' --input '" + csv + "' --output '" + out + "'");
    EXPECT_EQ(r.code, 4) << out << ": " << r.err;
    EXPECT_TRUE(has(r.err, "same file")) << r.err;
    EXPECT_TRUE(has(r.err, out)) << r.err;
    EXPECT_TRUE(slurp(csv) == recording) << out << ": the recording was changed";
    EXPECT_TRUE(slurp(cfg) == settings) << out << ": the configuration was changed";
  }
  // stdout redirected onto the recording (append, so that the shell does not truncate it)
  const Outcome r =
      run("replay --config '" + cfg + "' --input '" + csv + "' --output - >>'" + csv + "'");
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_TRUE(slurp(csv) == recording) << "the recording was changed";
}

TEST_F(Cli, ReplayThatFailsToWriteLeavesTheExistingOutputUntouched) {
  const std::string csv = small_csv();
  const std::string cfg = kSource + "/config/vessels/otter.yaml";
  const std::string jsonl = path("out.jsonl");
  spit(jsonl, "the previous run's output\n");
  // A 4 KiB file-size limit (SIGXFSZ ignored, so write(2) fails with EFBIG) stops the replay
  // part-way through its output.
  const Outcome r =
      run("replay --config '" + cfg + "' --input '" + csv + "' --output '" + jsonl + "'",
          "trap '' XFSZ; ulimit -f 4; ");
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_TRUE(has(r.err, jsonl)) << r.err;
  EXPECT_TRUE(has(r.err, std::strerror(EFBIG))) << r.err;
  EXPECT_EQ(slurp(jsonl), "the previous run's output\n");
  // no temporary file is left behind
  const Outcome ls =
      shell("ls -A '" + dir_ +
            "' | grep -v -x -e small.csv -e out.jsonl -e stdout.txt -e stderr.txt || true");
  EXPECT_EQ(ls.out, "");

  // A successful run replaces it, through a symlink the link stays and its target changes.
  ASSERT_EQ(::symlink(jsonl.c_str(), path("link.jsonl").c_str()), 0);
  const Outcome ok = run("replay --config '" + cfg + "' --input '" + csv + "' --output '" +
                         path("link.jsonl") + "'");
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_EQ(parse_lines(slurp(jsonl)).back().at("type").str, "summary");
  struct stat st {};
  ASSERT_EQ(::lstat(path("link.jsonl").c_str(), &st), 0);
  EXPECT_TRUE(S_ISLNK(st.st_mode));
}

/// The CSV text with the time field of data rows [first, last] (1-based, header excluded)
/// replaced by `t`, and the rows in `repeat` written twice.
std::string with_times(const std::string& csv, int first, int last, const std::string& t,
                       const std::set<int>& repeat = {}) {
  std::istringstream in(csv);
  std::string line, out;
  std::getline(in, line);
  out = line + "\n";
  for (int row = 1; std::getline(in, line); ++row) {
    if (row >= first && row <= last) line = t + line.substr(line.find(','));
    out += line + "\n";
    if (repeat.count(row)) out += line + "\n";
  }
  return out;
}

TEST_F(Cli, ReplayOfMostlyRejectedRowsExitsWith5) {
  const std::string cfg = kSource + "/config/vessels/otter.yaml";
  const std::string csv = slurp(small_csv());  // 301 rows, t = 0 .. 30 s
  // The INS clock sticks at 5 s from row 52 on: 250 rows do not advance.
  spit(path("stuck.csv"), with_times(csv, 52, 301, "5"));
  const std::string jsonl = path("stuck.jsonl");
  Outcome r = run("replay --config '" + cfg + "' --input '" + path("stuck.csv") + "' --output '" +
                  jsonl + "'");
  EXPECT_EQ(r.code, 5) << r.err;
  EXPECT_TRUE(has(r.err, "250 of 301 rows")) << r.err;
  EXPECT_TRUE(has(r.err, "stuck.csv:53")) << r.err;  // the first rejected row's line
  EXPECT_TRUE(has(r.err, "error")) << r.err;
  const auto recs = parse_lines(slurp(jsonl));  // the records are still written
  ASSERT_FALSE(recs.empty());
  EXPECT_EQ(recs.back().at("rejected").num, 250.0);

  // Three rows recorded twice: a warning, exit 0 (dropped as duplicates, not rejected).
  spit(path("dup.csv"), with_times(csv, 0, 0, "", {100, 200, 250}));
  r = run("replay --config '" + cfg + "' --input '" + path("dup.csv") + "' --output '" + jsonl +
          "'");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(has(r.err, "warn")) << r.err;
  EXPECT_TRUE(has(r.err, "3 of 304 rows")) << r.err;
  EXPECT_TRUE(has(r.err, "dup.csv:102")) << r.err;
}

TEST_F(Cli, ReplayWarnsOfUnitMistakesAndSaysWhyItDidNotConverge) {
  const std::string cfg = kSource + "/config/vessels/otter.yaml";
  std::istringstream in(slurp(small_csv()));  // 30 s at 10 Hz
  std::string line, ms, deg, empty;
  std::getline(in, line);
  ms = deg = empty = line + "\n";
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    f.resize(11);
    const auto row = [&f] {
      std::string s;
      for (const std::string& x : f) s += (s.empty() ? "" : ",") + x;
      return s + "\n";
    };
    const std::string t = f[0], delta = f[3];
    f[0] = std::to_string(std::stod(t) * 1000.0);
    ms += row();
    f[0] = t;
    f[3] = std::to_string(std::stod(delta) * 180.0 / M_PI);
    deg += row();
    f[3] = "";
    empty += row();
  }
  const std::pair<const char*, const std::string*> cases[] = {
      {"probably in milliseconds", &ms}, {"probably in degrees", &deg}, {"no value", &empty}};
  for (const auto& [expect, text] : cases) {
    spit(path("in.csv"), *text);
    const Outcome r = run("replay --config '" + cfg + "' --input '" + path("in.csv") +
                          "' --output '" + path("out.jsonl") + "'");
    // Stamps in milliseconds jump 100 "s" a sample: the engine's clock rejects each jump as
    // an outlier, so most rows are rejected (exit 5); the other mistakes replay (exit 0).
    EXPECT_EQ(r.code, text == &ms ? 5 : 0) << r.err;
    EXPECT_TRUE(has(r.err, "warning: " + path("in.csv") + ": column")) << r.err;
    EXPECT_TRUE(has(r.err, expect)) << r.err;
    EXPECT_TRUE(has(r.err, "has not converged")) << r.err;
  }
}

TEST_F(Cli, FileErrorsGiveTheSystemsReason) {
  const std::string cfg = kSource + "/config/vessels/otter.yaml";
  const std::string nowhere = path("no/such/dir/out.csv");
  Outcome r = run("sim --vessel otter --duration 5 --output '" + nowhere + "'");
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_TRUE(has(r.err, nowhere)) << r.err;
  EXPECT_TRUE(has(r.err, std::strerror(ENOENT))) << r.err;
  // sim's output cut short by a 4 KiB file-size limit
  r = run("sim --vessel otter --duration 60 --output '" + path("big.csv") + "'",
          "trap '' XFSZ; ulimit -f 4; ");
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_TRUE(has(r.err, std::strerror(EFBIG))) << r.err;
  const std::string csv = small_csv();
  r = run("replay --config '" + cfg + "' --input '" + csv + "' --output '" + nowhere + "'");
  EXPECT_EQ(r.code, 4) << r.err;
  EXPECT_TRUE(has(r.err, std::strerror(ENOENT))) << r.err;
  r = run("replay --config '" + path("none.yaml") + "' --input '" + csv + "'");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(has(r.err, std::strerror(ENOENT))) << r.err;
  r = run("replay --config '" + cfg + "' --input '" + path("none.csv") + "'");
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_TRUE(has(r.err, std::strerror(ENOENT))) << r.err;
}

TEST_F(Cli, SimFaultsAndOptions) {
  const std::string csv = path("f.csv");
  Outcome r =
      run("sim --vessel mariner --scenario healthy --rate 5 --duration 12 --seed 4 "
          "--steering sine --noise-scale 0 --fault gyro:stuck:2:4 "
          "--fault accelerometer:bias:6:8:0.1 --output '" +
          csv + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(has(r.err, "gyro:stuck:2:4")) << r.err;
  std::istringstream in(slurp(csv));
  std::string line;
  std::getline(in, line);
  int rows = 0, stuck = 0, bias = 0;
  while (std::getline(in, line)) {
    ++rows;
    if (has(line, ",,stuck")) ++stuck;
    if (has(line, ",bias,")) ++bias;
  }
  EXPECT_EQ(rows, 61);
  EXPECT_EQ(stuck, 10);
  EXPECT_EQ(bias, 10);

  r = run("sim --fault gyro:wobble:1:2:3 --output '" + csv + "'");
  EXPECT_EQ(r.code, 64);
  EXPECT_TRUE(has(r.err, "gyro:wobble:1:2:3")) << r.err;
  r = run("sim --vessel titanic --output '" + csv + "'");
  EXPECT_EQ(r.code, 64);
  EXPECT_TRUE(has(r.err, "titanic")) << r.err;
}

TEST_F(Cli, VesselsListsTheShippedModels) {
  const Outcome r = run("vessels");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(has(r.out, "mariner")) << r.out;
  EXPECT_TRUE(has(r.out, "otter")) << r.out;
  EXPECT_TRUE(has(r.out, "B:")) << r.out;
  EXPECT_TRUE(has(r.out, "Fossen")) << r.out;
}

// usv-fdi plot draws what the records say: every curve and every fault event of the paper's
// scenario (noise-free, as the golden replay), found by its id in the SVG.
TEST_F(Cli, PlotDrawsThePapersFiguresWithEveryEventAndInjectedFault) {
  const std::string csv = path("paper.csv"), jsonl = path("paper.jsonl");
  ASSERT_EQ(run("sim --vessel otter --scenario paper --rate 10 --noise-scale 0 --seed 1 "
                "--output '" +
                csv + "'")
                .code,
            0);
  const Outcome replay = run("replay --config '" + kSource + "/config/scenarios/paper.yaml' " +
                             "--input '" + csv + "' --output '" + jsonl + "' --signals 0.5");
  ASSERT_EQ(replay.code, 0) << replay.err;

  // Signal records every 0.5 s of data time (0 to 100 s at 10 Hz: t = 0, then every 5th row).
  std::vector<double> signal_t;
  std::vector<std::pair<std::string, std::string>> events;  // (state, sensor)
  for (const js::Value& rec : parse_lines(slurp(jsonl))) {
    const std::string type = rec.at("type").str;
    if (type == "event") events.emplace_back(rec.at("state").str, rec.at("sensor").str);
    if (type != "signal") continue;
    signal_t.push_back(rec.at("t").num);
    EXPECT_EQ(rec.at("j").arr.size(), 2u);
    EXPECT_EQ(rec.at("threshold").arr.size(), 2u);
    EXPECT_TRUE(rec.has("c_a") && rec.has("c_g") && rec.has("armed") && rec.has("mismatch"));
  }
  ASSERT_EQ(signal_t.size(), 201u);
  for (std::size_t i = 1; i < signal_t.size(); ++i) {
    EXPECT_NEAR(signal_t[i] - signal_t[i - 1], 0.5, 1e-6) << i;
  }
  ASSERT_EQ(events.size(), 4u);  // both faults raised and cleared

  const std::string out = path("figs");
  const Outcome r = run("plot --input '" + jsonl + "' --csv '" + csv + "' --format svg " +
                        "--truth -0.883024,-0.438614,-1.55172,-1.16124 --output '" + out + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out, out + "/fig1-estimate.svg\n" + out + "/fig2-signals.svg\n");
  const std::string fig1 = slurp(out + "/fig1-estimate.svg");
  for (const char* id : {"error-a1", "error-a2", "error-a3", "error-a4", "time-converged"}) {
    EXPECT_TRUE(has(fig1, std::string("id=\"") + id + "\"")) << id;
  }
  EXPECT_TRUE(has(fig1, "estimation error of A"));
  const std::string fig2 = slurp(out + "/fig2-signals.svg");
  for (const char* id :
       {"j-accelerometer", "j-gyro", "threshold-accelerometer", "threshold-gyro", "c-accelerometer",
        "c-gyro", "time-armed", "fault-gyro-0", "fault-accelerometer-1"}) {
    EXPECT_TRUE(has(fig2, std::string("id=\"") + id + "\"")) << id;
  }
  EXPECT_FALSE(has(fig2, "id=\"fault-gyro-1\"")) << "one gyro fault was injected";
  for (const auto& [state, sensor] : events) {
    const std::string id = "id=\"event-" + state + "-" + sensor + "-";
    EXPECT_TRUE(has(fig2, id)) << id;
  }

  // PNG, the default; Â over time without --truth; no Fig. 2 without signal records.
  const std::string plain = path("plain.jsonl");
  ASSERT_EQ(run("replay --config '" + kSource + "/config/scenarios/paper.yaml' --input '" + csv +
                "' --output '" + plain + "'")
                .code,
            0);
  const Outcome p = run("plot --input '" + plain + "' --output '" + path("png") + "'");
  ASSERT_EQ(p.code, 0) << p.err;
  EXPECT_EQ(p.out, path("png") + "/fig1-estimate.png\n");
  EXPECT_TRUE(has(p.err, "no signal record: no Fig. 2 (replay with --signals S")) << p.err;
  EXPECT_EQ(slurp(path("png") + "/fig1-estimate.png").substr(0, 8), "\x89PNG\r\n\x1a\n");
}

TEST_F(Cli, PlotNamesWhatIsWrongWithItsInput) {
  const auto plot = [this](const std::string& args, const std::string& env = "") {
    return run("plot " + args, "cd '" + dir_ + "' && " + env);
  };
  const std::string good =
      R"({"type":"estimate","t":0,"a":[1,2,3,4],"converged":false,"armed":false})";
  spit(path("bad.jsonl"), good + "\noops\n");
  Outcome r = plot("--input bad.jsonl");
  EXPECT_EQ(r.code, 3);
  EXPECT_TRUE(has(r.err, "bad.jsonl:2: not a JSON record")) << r.err;

  spit(path("short.jsonl"), good + "\n" + R"({"type":"estimate","t":1,"a":[1,2]})" + "\n");
  r = plot("--input short.jsonl");
  EXPECT_EQ(r.code, 3);
  EXPECT_TRUE(has(r.err, "short.jsonl:2: estimate record: 'a' must be an array of 4 numbers"))
      << r.err;

  spit(path("signal.jsonl"), R"({"type":"signal","t":1,"j":[1,2],"c_a":0,"c_g":1})"
                             "\n");
  r = plot("--input signal.jsonl");
  EXPECT_EQ(r.code, 3);
  EXPECT_TRUE(has(r.err,
                  "signal.jsonl:1: signal record: 'threshold' must be an array of 2 "
                  "numbers [accelerometer, gyro], got missing"))
      << r.err;

  spit(path("summary.jsonl"), R"({"type":"summary","samples":0})"
                              "\n");
  r = plot("--input summary.jsonl");
  EXPECT_EQ(r.code, 3);
  EXPECT_TRUE(has(r.err, "summary.jsonl: no estimate or signal record")) << r.err;

  r = plot("--input missing.jsonl");
  EXPECT_EQ(r.code, 3);
  EXPECT_TRUE(has(r.err, "missing.jsonl: cannot be read: No such file or directory")) << r.err;

  spit(path("ok.jsonl"), good + "\n");
  spit(path("nofaults.csv"), "t,v,r,delta\n0,0,0,0\n");
  r = plot("--input ok.jsonl --csv nofaults.csv");
  EXPECT_EQ(r.code, 3);
  EXPECT_TRUE(has(r.err, "nofaults.csv:1: no fault_a or fault_g column")) << r.err;

  r = plot("--input ok.jsonl --truth 1,2,x,4");
  EXPECT_EQ(r.code, 64);
  EXPECT_TRUE(has(r.err,
                  "--truth: need four finite numbers a1,a2,a3,a4 (A row-major), got "
                  "'1,2,x,4'"))
      << r.err;
  EXPECT_EQ(plot("--input ok.jsonl --truth 1,2,3").code, 64);
  EXPECT_EQ(plot("--input ok.jsonl --truth 1,2,3,4,").code, 64);
  EXPECT_EQ(plot("--input ok.jsonl --truth 0x1p0,2,3,4").code, 64);
  EXPECT_EQ(plot("--input ok.jsonl --format jpg").code, 64);

  spit(path("file"), "");
  r = plot("--input ok.jsonl --output file/figs");
  EXPECT_EQ(r.code, 4);
  EXPECT_TRUE(has(r.err, "file/figs: cannot create the directory")) << r.err;

  r = plot("--input ok.jsonl", "USV_FDI_PYTHON=/nonexistent/python3 ");
  EXPECT_EQ(r.code, 1);
  EXPECT_TRUE(has(r.err, "needs python3 and python3-matplotlib")) << r.err;
  EXPECT_TRUE(has(r.err, "cannot start /nonexistent/python3")) << r.err;
}

TEST_F(Cli, UsageErrors) {
  EXPECT_EQ(run("").code, 64);
  EXPECT_EQ(run("frobnicate").code, 64);
  EXPECT_EQ(run("replay --input x.csv").code, 64);
  EXPECT_EQ(run("--help").code, 0);
}

}  // namespace
}  // namespace usvfdi::io
