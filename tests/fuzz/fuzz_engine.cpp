// libFuzzer target: the FDI engine fed a realistic stream that the fuzzer corrupts (issue 4, "bad
// input gets a clear answer ... and no crash").
//
// The stream: the first 50 s of the paper's scenario on the Otter at 10 Hz (seed 1; 501 samples,
// gyro fault on 20-40 s) with the shipped config/scenarios/paper.yaml, so identification
// converges and isolation arms before 20 s and corruptions land on an armed detector (9 events
// uncorrupted). Short, so that an instrumented run takes milliseconds. The input is a list of
// 11-byte edits:
//   u16 row (mod rows), u8 op, f64 value (raw bits: NaN, Inf, huge, denormal all reachable)
//   op % 5: 0 set field, 1 multiply field, 2 swap the row with the next (out of order),
//           3 drop the row (gap), 4 repeat the previous row's time;  field = (op / 5) % 4: t v r
//           delta
// Every event is then acknowledged with its own sequence, and once with a sequence from the input.
// Contract under test: no crash, no exception, no sanitizer report; per instance the event
// sequence increases strictly; C_a and C_g stay in [0, 1] (or NaN).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "usv_fdi/core/engine.hpp"
#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/core/vessel.hpp"
#include "usv_fdi/io/config.hpp"

namespace {

[[noreturn]] void contract_broken(const std::string& what) {
  std::fprintf(stderr, "fuzz_engine: contract broken: %s\n", what.c_str());
  std::abort();
}

struct Fixture {
  usvfdi::EngineConfig cfg;
  std::vector<usvfdi::Sample> stream;
  Fixture() {
    cfg = usvfdi::io::load_engine_config(USV_FDI_SOURCE_DIR "/config/scenarios/paper.yaml");
    usvfdi::SimConfig sim = usvfdi::paper_scenario(usvfdi::otter(), 10.0, 1);
    sim.duration = 50.0;
    const auto rows = usvfdi::simulate(sim);
    for (const auto& r : rows) stream.push_back({r.t, r.v, r.r, r.delta});
  }
};

double& field(usvfdi::Sample& s, unsigned f) {
  switch (f % 4) {
    case 0:
      return s.t;
    case 1:
      return s.v;
    case 2:
      return s.r;
    default:
      return s.delta;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const Fixture fx;
  std::vector<usvfdi::Sample> s = fx.stream;
  std::vector<bool> dropped(s.size(), false);
  const std::size_t n = s.size();
  std::uint64_t bogus_sequence = 0;
  for (std::size_t at = 0; at + 11 <= size; at += 11) {
    std::uint16_t row16 = 0;
    std::memcpy(&row16, data + at, 2);
    const std::size_t row = row16 % n;
    const unsigned op = data[at + 2];
    double value = 0.0;
    std::memcpy(&value, data + at + 3, 8);
    std::memcpy(&bogus_sequence, data + at + 3, 8);
    const unsigned f = (op / 5) % 4;
    switch (op % 5) {
      case 0:
        field(s[row], f) = value;
        break;
      case 1:
        field(s[row], f) *= value;
        break;
      case 2:
        if (row + 1 < n) std::swap(s[row], s[row + 1]);
        break;
      case 3:
        dropped[row] = true;
        break;
      default:
        if (row > 0) s[row].t = s[row - 1].t;
        break;
    }
  }

  usvfdi::FdiEngine engine(fx.cfg);
  std::vector<usvfdi::FaultEvent> events;
  std::uint64_t last_sequence[3] = {0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    if (dropped[i]) continue;
    events.clear();
    engine.process(s[i], &events);
    for (const auto& e : events) {
      const int k = static_cast<int>(e.sensor);
      if (k < 0 || k > 2) contract_broken("event for an invalid sensor");
      if (e.sequence <= last_sequence[k]) {
        contract_broken("sequence did not increase: " + std::to_string(e.sequence) + " after " +
                        std::to_string(last_sequence[k]));
      }
      last_sequence[k] = e.sequence;
      if (e.c_a < 0.0 || e.c_a > 1.0 || e.c_g < 0.0 || e.c_g > 1.0) {
        contract_broken("C_a/C_g outside [0, 1]: " + std::to_string(e.c_a) + ", " +
                        std::to_string(e.c_g));
      }
      usvfdi::FaultEvent after;
      (void)engine.acknowledge(e.sensor, e.sequence, s[i].t, "fuzz", &after);
      if (after.sequence > 0) last_sequence[k] = std::max(last_sequence[k], after.sequence);
    }
  }
  usvfdi::FaultEvent after;
  (void)engine.acknowledge(usvfdi::Sensor::kGyro, bogus_sequence, 1e9, "fuzz", &after);
  return 0;
}
