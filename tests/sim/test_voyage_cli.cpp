// usv-fdi sim with voyage scenarios, end to end: the CSV, its determinism, replay of it, and
// the messages on bad options.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

#include "support/run_cli.hpp"

namespace {
using usvfdi::testing_cli::kExe;
using usvfdi::testing_cli::kSource;
using usvfdi::testing_cli::Outcome;
using usvfdi::testing_cli::slurp;

class VoyageCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = ::testing::TempDir() + "usv_fdi_voyage_" + info->name() + "_" +
           std::to_string(::getpid()) + "/";
    ASSERT_EQ(std::system(("mkdir -p '" + dir_ + "'").c_str()), 0);
  }
  void TearDown() override {
    if (HasFailure()) return;
    EXPECT_EQ(std::system(("rm -rf '" + dir_ + "'").c_str()), 0);
  }
  std::string path(const std::string& name) const { return dir_ + name; }
  Outcome run(const std::string& args) const {
    return usvfdi::testing_cli::run_shell("'" + kExe + "' " + args, dir_);
  }
  std::string dir_;
};

TEST_F(VoyageCli, WritesTheSimColumnsAndUAndTheSameSeedGivesTheSameFile) {
  const std::string args =
      "sim --vessel otter --scenario voyage --rate 10 --duration 200 --sea-state 3 "
      "--current 0.2 --wind 1 --sensor mems --fault-sigma gyro:bias:100:120:10 --output ";
  ASSERT_EQ(run(args + "'" + path("a.csv") + "'").code, 0);
  const Outcome b = run(args + "'" + path("b.csv") + "'");
  ASSERT_EQ(b.code, 0) << b.err;
  const std::string a = slurp(path("a.csv"));
  EXPECT_EQ(a, slurp(path("b.csv")));
  EXPECT_EQ(a.rfind("t,v,r,delta,v_true,r_true,delta_true,psi,psi_ref,fault_a,fault_g,u,", 0), 0u);
  EXPECT_NE(a.find(",bias,"), std::string::npos);
  EXPECT_NE(b.err.find("linearised B = [0.165394, -2.194]"), std::string::npos) << b.err;
  EXPECT_NE(b.err.find("fault gyro:bias:100:120:0.005"), std::string::npos) << b.err;
  const Outcome c = run(args + "'" + path("c.csv") + "' --seed 2");
  ASSERT_EQ(c.code, 0) << c.err;
  EXPECT_NE(a, slurp(path("c.csv")));
}

TEST_F(VoyageCli, ReplayReadsAVoyageCsv) {
  ASSERT_EQ(run("sim --vessel otter --scenario course --rate 10 --duration 120 --sensor mems "
                "--output '" +
                path("v.csv") + "'")
                .code,
            0);
  const Outcome r = run("replay --config '" + kSource + "/config/vessels/otter.yaml' --input '" +
                        path("v.csv") + "'");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("\"type\":\"summary\""), std::string::npos);
  EXPECT_NE(r.out.find("\"complete\":true"), std::string::npos);
}

// The Otter's yaw rate answers the rudder within a second: at 10 Hz a zigzag bends the gyro
// channel more within the jump check's windows than its line extrapolates, which the check
// took for a step (22-34 false gyro raises in 20 minutes of seeds 1 and 2 before it discounted
// the hull's own bend, JumpParams::bend_margin and bend_rate; seed 5 was not looked at while
// tuning them).
TEST_F(VoyageCli, AHealthyOtterVoyageOfZigzagsAndTurnsAt10HzRaisesNothing) {
  for (const char* seed : {"1", "2", "5"}) {
    SCOPED_TRACE(std::string("seed ") + seed);
    const std::string csv = path(std::string("healthy") + seed + ".csv");
    const std::string jsonl = path(std::string("healthy") + seed + ".jsonl");
    ASSERT_EQ(run(std::string("sim --vessel otter --scenario voyage --rate 10 --seed ") + seed +
                  " --output '" + csv + "'")
                  .code,
              0);
    const Outcome r = run("replay --config '" + kSource + "/config/vessels/otter.yaml' --input '" +
                          csv + "' --output '" + jsonl + "'");
    ASSERT_EQ(r.code, 0) << r.err;
    const std::string out = slurp(jsonl);
    const std::size_t summary = out.rfind("{\"type\":\"summary\"");
    ASSERT_NE(summary, std::string::npos);
    EXPECT_NE(out.find("\"raised\":{\"accelerometer\":0,\"gyro\":0,\"unknown\":0}", summary),
              std::string::npos)
        << out.substr(summary);
    EXPECT_NE(out.find("\"converged\":true", summary), std::string::npos) << out.substr(summary);
  }
}

TEST_F(VoyageCli, BadVoyageOptionsAreNamed) {
  const std::string out = " --output '" + path("x.csv") + "'";
  struct Case {
    std::string args, says;
  };
  const Case cases[] = {
      {"--scenario course --sea-state 2", "sea state 2: expected 0 (calm), 3, 4, 5 or 6"},
      {"--scenario paper --sea-state 4", "need a voyage scenario"},
      {"--scenario course --sensor gyro.gm=oops", "--sensor 'gyro.gm=oops': not a number: 'oops'"},
      {"--scenario course --sensor fancy", "--sensor 'fancy': unknown preset"},
      {"--scenario course --current fast", "--current 'fast': expected SPEED[:SET_DEG]"},
      {"--scenario course --wind 1:-2", "--wind '1:-2'"},
      {"--scenario course --dither 1:0", "--dither '1:0'"},
      {"--scenario course --steering sine", "--steering applies to the classic scenarios"},
      {"--scenario course --wave-period 8", "--wave-period needs a --sea-state"},
      {"--scenario course --fault-sigma gyro:bogus:1:2:3", "unknown kind 'bogus'"},
      {"--scenario zigzag10 --side left", "--side"},
      {"--scenario paper --side port", "need a voyage scenario"},
  };
  const Outcome zoo = run("sim --vessel container --scenario paper" + out);
  EXPECT_EQ(zoo.code, 64);
  EXPECT_NE(zoo.err.find("the classic scenarios (paper, healthy, faults) run the shipped vessels"),
            std::string::npos)
      << zoo.err;
  for (const Case& c : cases) {
    const Outcome r = run("sim --vessel otter " + c.args + out);
    EXPECT_EQ(r.code, 64) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.says), std::string::npos) << c.args << "\n" << r.err;
  }
}

}  // namespace
