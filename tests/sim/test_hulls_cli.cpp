// `usv-fdi vessels` and `usv-fdi vessels --yaml NAME`: the real binary; the printed
// configuration carries the linearised B and loads in the real `usv-fdi replay`.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "usv_fdi/sim/hulls.hpp"
#include "usv_fdi/sim/manoeuvre.hpp"

namespace usvfdi::sim {
namespace {

/// Runs the binary with args; returns its exit status and stdout.
int run(const std::string& args, std::string* out) {
  const std::string cmd = std::string(USV_FDI_EXE) + " " + args + " 2>/dev/null";
  FILE* p = popen(cmd.c_str(), "r");
  if (p == nullptr) return -1;
  char buf[4096];
  out->clear();
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out->append(buf, n);
  const int status = pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(VesselsCli, ListsEveryHullAtEverySpeedWithItsSource) {
  std::string out;
  ASSERT_EQ(run("vessels", &out), 0);
  for (const ZooEntry& e : zoo()) {
    EXPECT_NE(out.find("\n" + e.name + " "), std::string::npos) << e.name;
    EXPECT_NE(out.find(e.hull->source()), std::string::npos) << e.name;
  }
  EXPECT_NE(out.find("course-unstable"), std::string::npos);
}

/// The two numbers of the `  B: [b1, b2]` line of a printed configuration.
bool parse_B(const std::string& yaml, Vec2* B) {
  const std::size_t at = yaml.find("\nmodel:\n  B: [");
  return at != std::string::npos &&
         std::sscanf(yaml.c_str() + at, "\nmodel:\n  B: [%lf, %lf]", &(*B)(0), &(*B)(1)) == 2;
}

TEST(VesselsCli, YamlCarriesTheLinearisedBOfEveryHullAtEverySpeed) {
  for (const ZooEntry& e : zoo()) {
    for (double U : e.speeds) {
      std::string out;
      ASSERT_EQ(run("vessels --yaml " + e.name + " --speed " + std::to_string(U), &out), 0)
          << e.name;
      Vec2 B;
      ASSERT_TRUE(parse_B(out, &B)) << out;
      const Linearisation l = linearise(*e.hull, std::stod(std::to_string(U)));
      for (int i = 0; i < 2; ++i) {
        EXPECT_NEAR(B(i), l.B(i), 1e-5 * std::abs(l.B(i))) << e.name << " U=" << U;
      }
    }
  }
}

TEST(VesselsCli, ReplayRunsWithThePrintedConfigurationOnTheHullsOwnZigzag) {
  // GIVEN the configuration printed for the course-unstable KVLCC2 (replay loads it with
  // the project's config loader, which refuses anything malformed) and a 10/10 zigzag of
  // that hull at 10 Hz written as the CSV replay reads
  const std::string dir = ::testing::TempDir();
  std::string yaml;
  ASSERT_EQ(run("vessels --yaml kvlcc2", &yaml), 0);
  std::ofstream(dir + "kvlcc2.yaml") << yaml;
  const Hull& h = *find_hull("kvlcc2")->hull;
  std::ofstream csv(dir + "kvlcc2_zigzag.csv");
  csv << "t,v,r,delta\n";
  ManoeuvreState s;
  s.x.u = h.nominal_speed();
  const double sign = starboard_rudder_sign(h, s.x.u), d = 10 * M_PI / 180;
  double side = 1.0;
  for (int k = 0; k < 1200; ++k) {
    if (side * s.psi >= d) side = -side;
    csv << 0.1 * k << "," << s.x.v << "," << s.x.r << "," << s.delta << "\n";
    for (int i = 0; i < 5; ++i) s = manoeuvre_step(h, s, sign * side * d, 1.0, 0.02);
  }
  csv.close();
  // WHEN usv-fdi replay runs it THEN it accepts the configuration and writes its summary
  std::string out;
  ASSERT_EQ(
      run("replay --config " + dir + "kvlcc2.yaml --input " + dir + "kvlcc2_zigzag.csv", &out), 0);
  EXPECT_NE(out.find("\"summary\""), std::string::npos) << out.substr(0, 400);
}

TEST(VesselsCli, YamlRefusesAnUnknownHullAndAnUnreachableSpeed) {
  std::string out;
  EXPECT_NE(run("vessels --yaml no-such-hull", &out), 0);
  EXPECT_TRUE(out.empty());
  EXPECT_NE(run("vessels --yaml kvlcc2 --speed 50", &out), 0);
}

}  // namespace
}  // namespace usvfdi::sim
