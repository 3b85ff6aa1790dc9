// `usv-fdi vessels` and `usv-fdi vessels --yaml NAME`: the real binary; the printed
// configuration loads with the project's config loader and carries the linearised B.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "usv_fdi/io/config.hpp"
#include "usv_fdi/sim/hulls.hpp"

namespace usvfdi::sim {
namespace {

/// Runs the binary with args; returns its exit status and stdout.
int run(const std::string& args, std::string* out) {
  const std::string cmd = std::string(USV_FDI_BINARY) + " " + args + " 2>/dev/null";
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

TEST(VesselsCli, YamlLoadsWithTheConfigLoaderAndCarriesTheLinearisedB) {
  for (const ZooEntry& e : zoo()) {
    for (double U : e.speeds) {
      std::string out;
      ASSERT_EQ(run("vessels --yaml " + e.name + " --speed " + std::to_string(U), &out), 0)
          << e.name;
      const EngineConfig c = io::load_engine_config_from_string(out, e.name + ".yaml");
      const Linearisation l = linearise(*e.hull, std::stod(std::to_string(U)));
      for (int i = 0; i < 2; ++i) {
        EXPECT_NEAR(c.B(i), l.B(i), 1e-5 * std::abs(l.B(i))) << e.name << " U=" << U;
      }
    }
  }
}

TEST(VesselsCli, YamlRefusesAnUnknownHullAndAnUnreachableSpeed) {
  std::string out;
  EXPECT_NE(run("vessels --yaml no-such-hull", &out), 0);
  EXPECT_TRUE(out.empty());
  EXPECT_NE(run("vessels --yaml kvlcc2 --speed 50", &out), 0);
}

}  // namespace
}  // namespace usvfdi::sim
