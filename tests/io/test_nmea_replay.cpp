// Replay from NMEA logs and the simulator's NMEA output (issue 12, section 2): the round trip
// sim --nmea -> replay --input x.nmea against the CSV replay of the same voyage, bad lines,
// and the signs of r and delta through the sentences.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "json_lite.hpp"
#include "support/run_cli.hpp"
#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/io/nmea_log.hpp"

namespace usvfdi::io {
namespace {

namespace js = usvfdi::testing_json;
namespace cli = usvfdi::testing_cli;

/// A raised event of a replay: sensor and detection time [s since the voyage's start].
struct Raised {
  std::string sensor;
  double detection_time = 0.0;
};

class NmeaReplay : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = ::testing::TempDir() + "usv_fdi_nmea_" + info->name() + "_" +
           std::to_string(::getpid()) + "/";
    ASSERT_EQ(std::system(("mkdir -p '" + dir_ + "'").c_str()), 0);
  }
  void TearDown() override {
    if (!HasFailure()) std::system(("rm -rf '" + dir_ + "'").c_str());
  }
  std::string path(const std::string& name) const { return dir_ + name; }
  cli::Outcome run(const std::string& args) const {
    return testing_cli::run_shell("'" + cli::kExe + "' " + args, dir_);
  }
  /// Runs `usv-fdi sim ARGS --output NAME` in the test's folder; the log's text ("" on failure).
  std::string sim(const std::string& args, const std::string& name) const {
    const cli::Outcome r = run("sim " + args + " --output '" + path(name) + "'");
    EXPECT_EQ(r.code, 0) << r.err;
    return r.code == 0 ? cli::slurp(path(name)) : std::string();
  }
  /// Replays `input` with `config` (relative to the repository) into the JSON records.
  std::vector<js::Value> replay(const std::string& config, const std::string& input,
                                const std::string& extra = "", int expect_code = 0) const {
    const std::string out = path("out.jsonl");
    const cli::Outcome r = run("replay --config '" + cli::kSource + "/" + config + "' --input '" +
                               input + "' --output '" + out + "' " + extra);
    EXPECT_EQ(r.code, expect_code) << r.err;
    last_err_ = r.err;
    std::vector<js::Value> recs;
    std::istringstream in(cli::slurp(out));
    for (std::string line; std::getline(in, line);) recs.push_back(js::parse(line));
    return recs;
  }
  std::string dir_;
  mutable std::string last_err_;
};

/// The raised events, in order.
std::vector<Raised> raised(const std::vector<js::Value>& recs) {
  std::vector<Raised> out;
  for (const js::Value& v : recs) {
    if (v.at("type").str == "event" && v.at("state").str == "raised") {
      out.push_back({v.at("sensor").str, v.at("detection_time").num});
    }
  }
  return out;
}

bool has(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

/// "$BODY*hh\r\n" with its checksum.
std::string sentence(const std::string& body) {
  unsigned x = 0;
  for (char c : body) x ^= static_cast<unsigned char>(c);
  char hh[3];
  std::snprintf(hh, sizeof hh, "%02X", x);
  return "$" + body + "*" + hh + "\r\n";
}

TEST_F(NmeaReplay, PaperScenarioThroughNmeaRaisesAndIsolatesBothFaultsLikeTheCsvReplay) {
  // GIVEN the paper's scenario (Otter, 10 Hz) as CSV and as NMEA, noise-free as in the paper
  // and in the golden case `paper` (with the realistic noise, config/scenarios/paper.yaml
  // arms too late for the gyro fault, in both replays alike)
  const std::string paper = "--vessel otter --scenario paper --rate 10 --noise-scale 0 --seed 1";
  ASSERT_FALSE(sim(paper, "paper.csv").empty());
  const std::string log = sim(paper + " --nmea", "paper.nmea");
  EXPECT_EQ(log.rfind("\\s:HE0001,n:1,c:1767225600*", 0), 0u) << log.substr(0, 80);
  EXPECT_TRUE(has(log, "$HEROT,") && has(log, "$AGRSA,") && has(log, "$VDVBW,"));

  // WHEN both are replayed with the same configuration
  const auto csv = raised(replay("config/scenarios/paper.yaml", path("paper.csv")));
  const auto recs = replay("config/scenarios/paper.yaml", path("paper.nmea"));
  const auto nmea = raised(recs);
  EXPECT_TRUE(has(last_err_, "0 unusable")) << last_err_;

  // THEN the gyro fault, then the accelerometer fault, in both
  ASSERT_EQ(csv.size(), 2u);
  EXPECT_EQ(csv[0].sensor, "gyro");
  EXPECT_EQ(csv[1].sensor, "accelerometer");
  ASSERT_EQ(nmea.size(), csv.size());
  for (std::size_t i = 0; i < csv.size(); ++i) {
    EXPECT_EQ(nmea[i].sensor, csv[i].sensor) << i;
    // The NMEA replay sees the samples rounded to the sentences' digits (r to 1e-3 deg/min,
    // delta to 1e-3 deg, v to 1e-4 kn; its times, from TAG c: in ms, are the CSV's), so the
    // statistics differ in their last digits and a threshold may be crossed a sample or two
    // later or earlier: a tolerance of 0.5 s (5 samples), far below the 20 s faults.
    EXPECT_NEAR(nmea[i].detection_time, csv[i].detection_time, 0.5) << nmea[i].sensor;
  }
  const js::Value& sum = recs.back();
  EXPECT_EQ(sum.at("type").str, "summary");
  EXPECT_EQ(sum.at("samples").num, 1001.0);  // 100 s at 10 Hz, as the CSV
  EXPECT_EQ(sum.at("rejected").num, 0.0);
}

TEST_F(NmeaReplay, LostSentencesAreGapsNotTheOldValuesAgain) {
  // GIVEN the noise-free paper scenario as NMEA, with every 37th sample's three lines (ROT,
  // RSA, VBW: one datagram) lost
  const std::string log =
      sim("--vessel otter --scenario paper --rate 10 --noise-scale 0 --seed 1 --nmea", "p.nmea");
  std::istringstream in(log);
  std::string lossy;
  int k = 0;
  for (std::string line; std::getline(in, line); ++k) {
    if (k / 3 % 37 != 36) lossy += line + "\n";
  }
  {
    std::ofstream out(path("lossy.nmea"));
    out << lossy;
  }
  // WHEN it is replayed with each way of holding a value on the grid
  const auto due = replay("config/scenarios/paper.yaml", path("lossy.nmea"), "--nmea-hold due");
  const auto held =
      replay("config/scenarios/paper.yaml", path("lossy.nmea"), "--nmea-hold max-age");
  // THEN held until due, the lost samples are gaps: the gyro fault, then the
  // accelerometer fault, at their onsets, nothing else
  const auto d = raised(due);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].sensor, "gyro");
  EXPECT_NEAR(d[0].detection_time, 20.0, 1.0);
  EXPECT_EQ(d[1].sensor, "accelerometer");
  EXPECT_NEAR(d[1].detection_time, 60.0, 1.0);
  EXPECT_EQ(due.back().at("samples").num, 1001.0 - 27.0);  // 27 grid times without a sample
  // AND held up to the max age (the zero-order hold, the default), the old values again at those
  // grid times: every sample is there, and the voyage's faults are not what it raises
  const auto h = raised(held);
  EXPECT_EQ(held.back().at("samples").num, 1001.0);
  EXPECT_FALSE(h.size() == 2u && h[0].sensor == "gyro" && h[0].detection_time < 21.0 &&
               h[1].sensor == "accelerometer")
      << "the zero-order hold no longer disturbs the engine: the comparison shows nothing";
  // AND a hold that is neither is refused
  replay("config/scenarios/paper.yaml", path("lossy.nmea"), "--nmea-hold sometimes", 64);
  EXPECT_TRUE(has(last_err_, "--nmea-hold")) << last_err_;
}

TEST_F(NmeaReplay, HealthyVoyageThroughNmeaRaisesNothing) {
  EXPECT_TRUE(has(sim("--vessel otter --scenario healthy --rate 10 --duration 150 --seed 1 "
                      "--nmea --nmea-heading",
                      "healthy.nmea"),
                  "$HEHDT,"));
  const auto recs = replay("config/vessels/otter.yaml", path("healthy.nmea"));
  EXPECT_TRUE(raised(recs).empty());
  EXPECT_EQ(recs.back().at("samples").num, 1501.0);
  EXPECT_EQ(recs.back().at("events").num, 0.0);
  EXPECT_TRUE(has(last_err_, "0 unusable")) << last_err_;  // HDT is ignored, not unusable
}

TEST_F(NmeaReplay, CorruptedLinesAreCountedByReasonAndNeverStopTheReplay) {
  std::istringstream in(
      sim("--vessel otter --scenario paper --rate 10 --duration 30 --nmea", "short.nmea"));
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l + "\n");
  ASSERT_EQ(lines.size(), 903u);  // 301 samples, 3 sentences each
  const std::string tag = lines[300].substr(0, lines[300].find('$'));
  lines[300] = tag + sentence("HEROT,99999.000,A");  // absurd rate of turn
  lines[303] = tag + sentence("HEROT,1.000,V");      // status V
  std::string& bad = lines[306];
  bad[bad.size() - 3] = bad[bad.size() - 3] == '0' ? '1' : '0';           // checksum mismatch
  lines[309] = lines[309].substr(0, lines[309].rfind('*') - 3) + "\n";    // truncated: no checksum
  lines[312] = "\\s:HE0001,c:17672256*00\\" + sentence("HEROT,1.000,A");  // bad TAG checksum
  lines.push_back("garbage\n");
  lines.push_back(sentence("GPGGA,120000.00,5900.0,N,01000.0,E,1,08,1.0,0.0,M,0.0,M,,"));
  lines.push_back(sentence("XXROT,2.000,A"));  // unknown talker: fine (no TAG: latest time)
  {
    std::ofstream f(path("bad.nmea"), std::ios::binary);
    for (const std::string& l : lines) f << l;
  }
  const auto recs = replay("config/scenarios/paper.yaml", path("bad.nmea"));
  ASSERT_FALSE(recs.empty());
  EXPECT_TRUE(recs.back().at("complete").b);
  EXPECT_EQ(recs.back().at("samples").num, 301.0);
  for (const char* reason : {"1 out of range (first: line 301)", "1 status V (first: line 304)",
                             "1 checksum mismatch (first: line 307)",
                             "1 no checksum (first: line 310)", "1 bad TAG block (first: line 313)",
                             "1 no start character (first: line 904)", "6 of 906 lines"}) {
    EXPECT_TRUE(has(last_err_, reason)) << reason << "\n" << last_err_;
  }

  // The same log without its TAG blocks: no time unless a sentence rate is given.
  std::string plain;
  for (std::size_t i = 0; i < 903; ++i) {
    const std::string& l = lines[i];
    plain += l.find('$') == std::string::npos ? l : l.substr(l.find('$'));
  }
  {
    std::ofstream f(path("plain.nmea"), std::ios::binary);
    f << plain;
  }
  replay("config/scenarios/paper.yaml", path("plain.nmea"), "", 5);
  EXPECT_TRUE(has(last_err_, "plain.nmea:1: no time")) << last_err_;
  const auto timed = replay("config/scenarios/paper.yaml", path("plain.nmea"), "--nmea-rate 10");
  EXPECT_EQ(timed.back().at("samples").num, 301.0);
  EXPECT_NEAR(timed.back().at("duration_s").num, 30.0, 1e-9);

  // Mostly garbage: exit 5 naming the file and the first bad line.
  {
    std::ofstream f(path("junk.nmea"), std::ios::binary);
    f << lines[0] << lines[1] << lines[2];
    for (int i = 0; i < 10; ++i) f << "$HEROT,1.0,A*00\n";
  }
  replay("config/scenarios/paper.yaml", path("junk.nmea"), "", 5);
  EXPECT_TRUE(has(last_err_, "10 of 13 lines")) << last_err_;
  EXPECT_TRUE(has(last_err_, "junk.nmea:4: checksum mismatch")) << last_err_;
}

TEST_F(NmeaReplay, FormatNmeaReadsALogOfAnyName) {
  ASSERT_FALSE(
      sim("--vessel otter --scenario paper --rate 10 --duration 10 --nmea", "log.txt").empty());
  const auto recs = replay("config/scenarios/paper.yaml", path("log.txt"), "--format nmea");
  EXPECT_EQ(recs.back().at("samples").num, 101.0);

  // The same sentences as IEC 61162-450 datagrams, one a sample: "UdPbC", NUL, the TAG block
  // and ROT; RSA and VBW on the next lines without a TAG block (they share the datagram's).
  std::istringstream in(cli::slurp(path("log.txt")));
  std::string datagrams;
  std::size_t k = 0;
  for (std::string l; std::getline(in, l); ++k) {
    l.pop_back();  // the CR of the sim's CR LF
    datagrams += k % 3 == 0 ? std::string("UdPbC", 5) + '\0' + l : l.substr(l.find('$'));
    datagrams += "\r\n";
  }
  {
    std::ofstream f(path("datagrams.nmea"), std::ios::binary);
    f << datagrams;
  }
  const auto dg = replay("config/scenarios/paper.yaml", path("datagrams.nmea"));
  EXPECT_EQ(dg.back().at("samples").num, 101.0);
  EXPECT_EQ(dg.back().at("final_a").arr.at(0).num, recs.back().at("final_a").arr.at(0).num);
  EXPECT_TRUE(has(last_err_, "303 used")) << last_err_;
}

TEST_F(NmeaReplay, StarboardTurnOfAVoyageIsPositiveRotAndRsa) {
  // The voyage `turn` on the Otter: hold course, then a turning circle to starboard (the
  // default --side) with the rudder hard over from about 20 s to 55 s.
  std::istringstream in(
      sim("--vessel otter --scenario turn --rate 10 --duration 60 --nmea", "turn.nmea"));
  std::size_t k = 0, rot = 0, rsa = 0;
  for (std::string l; std::getline(in, l); ++k) {
    const std::string x = l.substr(l.find('$'));
    if (k < 3 * 300 || k >= 3 * 500) continue;  // t in [30, 50) s: in the turn
    if (x.rfind("$HEROT,", 0) == 0) {
      EXPECT_GT(std::stod(x.substr(7)), 0.0) << x;  // bow to starboard: r > 0
      ++rot;
    } else if (x.rfind("$AGRSA,", 0) == 0) {
      EXPECT_GT(std::stod(x.substr(7)), 0.0) << x;  // RSA > 0: turns the bow to starboard
      ++rsa;
    }
  }
  EXPECT_EQ(rot, 200u);
  EXPECT_EQ(rsa, 200u);
  // The replay reads it back with the Otter's B (b2 < 0: delta < 0 in the turn), raising
  // nothing on the saturated rudder or the quantised sentences.
  const auto recs = replay("config/vessels/otter.yaml", path("turn.nmea"));
  EXPECT_TRUE(raised(recs).empty());
  EXPECT_TRUE(has(last_err_, "0 unusable")) << last_err_;
}

// Signs: the simulator's samples written as sentences and read back agree within the
// rounding; a turn to starboard (r > 0) stays r > 0, and delta keeps the model's sign (RSA has
// the opposite sign for the Otter, whose b2 < 0).
TEST(NmeaRoundTrip, StarboardTurnGivesPositiveRAndTheRudderKeepsTheModelsSign) {
  const VesselModel& otter = usvfdi::otter();
  ASSERT_LT(otter.B(1), 0.0);
  Simulator sim(paper_scenario(otter, 10.0, 3));
  std::vector<SimRow> rows;
  auto text = std::make_unique<std::stringstream>();
  NmeaOutputOptions o;
  o.b2 = otter.B(1);
  o.surge_speed = otter.u0;
  NmeaSimWriter writer(*text, o);
  for (SimRow row; sim.next(&row);) {
    rows.push_back(row);
    writer.write(row);
  }
  // In the text: ROT has the sign of r, RSA the opposite sign of the Otter's delta.
  std::vector<std::string> lines;
  {
    std::istringstream all(text->str());
    for (std::string l; std::getline(all, l);) lines.push_back(l.substr(l.find('$')));
  }
  ASSERT_EQ(lines.size(), 3 * rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    if (std::fabs(rows[k].r) > 1e-3) {
      EXPECT_EQ(lines[3 * k][7] == '-', rows[k].r < 0) << lines[3 * k];  // after "$HEROT,"
    }
    if (std::fabs(rows[k].delta) > 1e-3) {
      EXPECT_EQ(lines[3 * k + 1][7] == '-', rows[k].delta > 0) << lines[3 * k + 1];  // $AGRSA,
    }
  }
  NmeaInputOptions in;
  in.b2 = otter.B(1);
  NmeaSampleReader reader(std::move(text), "round trip", in);
  std::size_t i = 0, starboard = 0, port = 0;
  for (Sample s; reader.next(&s); ++i) {
    ASSERT_LT(i, rows.size());
    const SimRow& row = rows[i];
    EXPECT_NEAR(s.t, row.t, 1e-9) << i;
    EXPECT_NEAR(s.r, row.r, 0.6e-3 * M_PI / 10800.0) << i;
    EXPECT_NEAR(s.delta, row.delta, 0.6e-3 * M_PI / 180.0) << i;
    EXPECT_NEAR(s.v, row.v, 0.6e-4 * 1852.0 / 3600.0) << i;
    EXPECT_NEAR(s.u, otter.u0, 1e-4) << i;
    if (row.r > 1e-3) {
      EXPECT_GT(s.r, 0.0) << i;
      ++starboard;
    }
    if (row.r < -1e-3) ++port;
    if (std::fabs(row.delta) > 1e-3) {
      EXPECT_EQ(s.delta > 0, row.delta > 0) << i;
    }
  }
  EXPECT_EQ(i, rows.size());
  EXPECT_GT(starboard, 50u);
  EXPECT_GT(port, 50u);
  EXPECT_TRUE(reader.stats().reasons.empty()) << reader.stats().describe();
}

}  // namespace
}  // namespace usvfdi::io
