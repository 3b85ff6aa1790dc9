#include "runner.hpp"

#include <unistd.h>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "usv_fdi/core/simulator.hpp"
#include "usv_fdi/io/config.hpp"
#include "usv_fdi/io/csv.hpp"
#include "usv_fdi/sim/hulls.hpp"
#include "usv_fdi/sim/voyage.hpp"

namespace usvfdi::bench {

namespace fs = std::filesystem;

const char* method_name(int m) {
  switch (m) {
    case kEngine:
      return "engine";
    case kPaper:
      return "paper";
    case kOracle:
      return "oracle";
    default:
      return "?";
  }
}

const std::vector<FaultKind>& standard_kinds() {
  static const std::vector<FaultKind> k = {FaultKind::kBias, FaultKind::kStuck, FaultKind::kDrift,
                                           FaultKind::kNoise, FaultKind::kScale};
  return k;
}

std::vector<FaultSpec> standard_faults(double sigma) {
  return {{FaultKind::kBias, 10.0 * sigma},
          {FaultKind::kStuck, 0.0},
          {FaultKind::kDrift, 10.0 * sigma / 30.0},
          {FaultKind::kNoise, std::sqrt(63.0) * sigma},
          {FaultKind::kScale, 0.5}};
}

void apply_fault(std::vector<Sample>* samples, const InjectedFault& f, double magnitude,
                 std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  double held = kNaN;
  for (Sample& s : *samples) {
    if (s.t < f.t_start || s.t >= f.t_end) continue;
    double& y = f.sensor == Sensor::kAccelerometer ? s.v : s.r;
    switch (f.kind) {
      case FaultKind::kBias:
        y += magnitude;
        break;
      case FaultKind::kDrift:
        y += magnitude * (s.t - f.t_start);
        break;
      case FaultKind::kNoise:
        y += magnitude * n01(rng);
        break;
      case FaultKind::kScale:
        y += magnitude * y;
        break;
      case FaultKind::kStuck:
        if (std::isnan(held)) held = y;
        y = held;
        break;
      default:
        throw std::invalid_argument(std::string("apply_fault: kind ") + to_string(f.kind) +
                                    " is not in the standard set");
    }
  }
}

std::vector<RecordedRun> load_hsva(const std::string& dir) {
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string n = e.path().filename().string();
    if (n.rfind("HSVA_", 0) == 0 && e.path().extension() == ".csv") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw std::runtime_error(dir + ": no HSVA_*.csv files");
  std::vector<RecordedRun> runs;
  for (const std::string& f : files) {
    io::CsvSampleReader reader(f);
    RecordedRun run;
    run.name = fs::path(f).stem().string();
    Sample s;
    while (reader.next(&s)) run.samples.push_back(s);
    if (run.samples.size() < 100) throw std::runtime_error(f + ": fewer than 100 rows");
    runs.push_back(std::move(run));
  }
  return runs;
}

HsvaModel load_hsva_model(const std::string& dir) {
  HsvaModel m;
  m.B = io::load_engine_config((fs::path(dir) / "kvlcc2_model.yaml").string()).B;
  // ../shared/realdata/kvlcc2-hsva/README.md, section "B": "The same linearisation gives
  // A ~ [[-0.103, -0.412], [-0.090, -0.394]]" (the published MMG model at model scale).
  m.A_ref << -0.103, -0.412, -0.090, -0.394;
  return m;
}

std::vector<Sample> concatenate(const std::vector<RecordedRun>& runs, double gap,
                                std::vector<double>* run_starts) {
  std::vector<Sample> out;
  double offset = 0.0;
  for (const RecordedRun& run : runs) {
    const double shift =
        out.empty() ? -run.samples.front().t : out.back().t + gap - run.samples.front().t;
    offset = shift;
    if (run_starts) run_starts->push_back(run.samples.front().t + offset);
    for (Sample s : run.samples) {
      s.t += offset;
      out.push_back(s);
    }
  }
  return out;
}

Vec2 recorded_noise(const std::vector<RecordedRun>& runs) {
  std::array<std::vector<double>, 2> d2;
  for (const RecordedRun& run : runs) {
    const auto& x = run.samples;
    for (std::size_t k = 1; k + 1 < x.size(); ++k) {
      d2[0].push_back(std::abs(x[k + 1].v - 2 * x[k].v + x[k - 1].v));
      d2[1].push_back(std::abs(x[k + 1].r - 2 * x[k].r + x[k - 1].r));
    }
  }
  Vec2 sigma;
  for (int i = 0; i < 2; ++i) sigma(i) = 1.4826 * quantile(d2[i], 0.5) / std::sqrt(6.0);
  return sigma;
}

Vec2 fault_sigma_floor() {
  const IsolationParams p;
  return Vec2(p.sigma_floor_v, p.sigma_floor_r);
}

std::string find_realdata(const std::string& source_dir, std::string* why) {
  std::vector<std::string> tried;
  fs::path p = fs::absolute(source_dir);
  for (int up = 0; up < 3 && !p.empty(); ++up) {
    const fs::path cand = p.parent_path() / "shared" / "realdata" / "kvlcc2-hsva";
    tried.push_back(cand.string());
    if (fs::is_directory(cand)) return cand.string();
    if (p == p.parent_path()) break;
    p = p.parent_path();
  }
  if (why) {
    *why =
        "the HSVA KVLCC2 data (shared/realdata/kvlcc2-hsva beside the repository) were not "
        "found; tried:";
    for (const auto& t : tried) *why += " " + t;
  }
  return {};
}

namespace {

// The INS of every simulated hull (the measurements: 1 cm/s and 0.03 deg/s).
constexpr double kInsSigmaV = 0.01;                      // [m/s]
constexpr double kDeg = 3.14159265358979323846 / 180.0;  // [rad]
constexpr double kInsSigmaR = 0.03 * kDeg;               // [rad/s]

std::uint64_t mix_seed(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::string rate_name(double hz) {
  std::ostringstream o;
  o << hz << " Hz";
  return o.str();
}

struct Subject {
  std::string name;
  std::shared_ptr<const sim::Hull> hull;
  sim::Linearisation lin;
};

/// Every hull a voyage can drive (sim::voyage_hull_names(): the vessel zoo, then the shipped
/// Otter, the linear model the engine's defaults were developed on) at its nominal speed.
std::vector<Subject> zoo_subjects() {
  std::vector<Subject> out;
  for (const std::string& name : sim::voyage_hull_names()) {
    std::shared_ptr<const sim::Hull> hull = sim::voyage_hull(name);
    if (!hull) throw std::logic_error("voyage hull '" + name + "' is listed but not made");
    out.push_back(Subject{name, hull, sim::linearise(*hull, hull->nominal_speed())});
  }
  return out;
}

}  // namespace

sim::VoyageConfig voyage_config(const sim::Hull& hull, const std::string& voyage) {
  sim::VoyageConfig c;
  if (voyage == "course/calm") {
    c.legs = sim::scenario_legs("course", hull);
    sim::sensor_preset("ideal", kInsSigmaV, kInsSigmaR, &c.sensors);
  } else if (voyage == "voyage/sea3/mems") {
    c.legs = sim::scenario_legs("voyage", hull);
    c.environment.sea = sim::sea_state(3);
    c.environment.current = 0.1;
    c.environment.current_sigma = 0.05;
    c.environment.wind = 0.5 * kDeg;
    c.environment.wind_sigma = 0.5 * kDeg;
    sim::sensor_preset("mems", kInsSigmaV, kInsSigmaR, &c.sensors);
  } else {
    throw std::invalid_argument("unknown benchmark voyage '" + voyage + "'");
  }
  return c;
}

namespace {

/// 5 s before the first leg that begins at or after t (legs by their nominal durations,
/// repeated as the voyage repeats them).
double onset_before_leg(const sim::Hull& hull, const std::string& voyage, double t) {
  const std::vector<sim::Leg> legs = voyage_config(hull, voyage).legs;
  double total = 0.0;
  for (const sim::Leg& l : legs) total += l.duration;
  if (!(total > 0)) return t;
  double b = std::floor(t / total) * total;
  for (;;) {
    for (const sim::Leg& l : legs) {
      if (b >= t) return b - 5.0;
      b += l.duration;
    }
  }
}

struct Plan {
  std::vector<double> rates;
  std::vector<std::string> voyages;
  int seeds = 1;
  double onset = 0.0, fault_len = 0.0, tail = 0.0;
  int healthy_seeds = 1;
  double healthy_len = 0.0;
};

Stream voyage_stream(const std::shared_ptr<const sim::Hull>& hull, const std::string& voyage,
                     double rate, std::uint64_t seed, double duration,
                     const std::vector<FaultInjection>& faults) {
  sim::VoyageConfig c = voyage_config(*hull, voyage);
  c.rate_hz = rate;
  c.duration = duration;
  c.seed = seed;
  c.faults = faults;
  Stream st;
  sim::Voyage run(hull, c);
  sim::VoyageRow row;
  st.samples.reserve(static_cast<std::size_t>(duration * rate) + 2);
  while (run.next(&row)) {
    // The surge speed as a log measures it (Sample::u; used with --speed only).
    st.samples.push_back(Sample{row.t, row.v, row.r, row.delta, row.u_true});
  }
  for (const FaultInjection& f : faults) {
    st.faults.push_back(InjectedFault{f.sensor, f.kind, f.t_start, f.t_end});
  }
  return st;
}

/// The run list's dimensions in the quick (CI) and the full mode; --seeds overrides both
/// seed counts.
Plan plan_of(const BenchOptions& opt) {
  Plan p;
  if (opt.quick) {
    p.rates = {10.0, 50.0};
    p.voyages = {"course/calm"};
    p.seeds = 1;
    p.onset = 200.0;
    p.fault_len = 60.0;
    p.tail = 60.0;
    p.healthy_seeds = 1;
    p.healthy_len = 600.0;
  } else {
    p.rates = {10.0, 50.0};
    p.voyages = {"course/calm", "voyage/sea3/mems"};
    p.seeds = 5;
    p.onset = 900.0;
    p.fault_len = 60.0;
    p.tail = 120.0;
    p.healthy_seeds = 3;
    p.healthy_len = 4 * 3600.0;
  }
  if (opt.seeds > 0) p.seeds = p.healthy_seeds = opt.seeds;
  return p;
}

/// --only: whether a table is run.
bool wanted(const BenchOptions& opt, const std::string& table) {
  return opt.only.empty() || table.find(opt.only) != std::string::npos;
}

/// What the runs of a zoo table share: the model, the INS noise, the voyages.
std::string zoo_note(const Subject& sub, const Plan& p) {
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "%s model at %.4g m/s (B and the oracle's A from its linearisation); INS "
                "white noise sigma_v = %.2g m/s, sigma_r = %.2g rad/s; voyages:",
                sub.hull->nonlinear() ? "nonlinear 3-DOF" : "linear", sub.lin.u0, kInsSigmaV,
                kInsSigmaR);
  std::string note = buf;
  for (const std::string& voyage : p.voyages) note += " " + voyage;
  return note;
}

/// The simulator's form of a fault of a case.
FaultInjection to_injection(const InjectedFault& f, double magnitude) {
  FaultInjection fi;
  fi.sensor = f.sensor;
  fi.kind = f.kind;
  fi.t_start = f.t_start;
  fi.t_end = f.t_end;
  fi.magnitude = magnitude;
  return fi;
}

/// One zoo table (a subject at a rate): on every voyage its healthy runs, then for every
/// seed each standard fault on each channel. Every case takes the next seed of *serial.
void add_zoo_table(const Subject& sub, double rate, const Plan& p, const std::string& table,
                   std::uint64_t* serial, std::vector<Case>* cases) {
  const std::string note = zoo_note(sub, p);
  // A case of this table on that voyage, with the next seed.
  const auto voyage_case = [&](const std::string& voyage) {
    Case c;
    c.table = table;
    c.note = note;
    c.subject = sub.name;
    c.voyage = voyage;
    c.rate_hz = rate;
    c.seed = mix_seed(++*serial);
    c.B = sub.lin.B;
    c.A_ref = sub.lin.A;
    return c;
  };
  for (const std::string& voyage : p.voyages) {
    for (int h = 0; h < p.healthy_seeds; ++h) {
      Case c = voyage_case(voyage);
      c.duration = p.healthy_len;
      c.make = [hull = sub.hull, voyage, rate, seed = c.seed, d = c.duration] {
        return voyage_stream(hull, voyage, rate, seed, d, {});
      };
      cases->push_back(std::move(c));
    }
    for (int s = 0; s < p.seeds; ++s) {
      // The onset moves with the seed, so that the faults meet different manoeuvres,
      // and lies 5 s before a leg begins: a scale error, invisible while the vessel
      // holds its course, meets a manoeuvre within the fault.
      const double onset = onset_before_leg(*sub.hull, voyage, p.onset + 61.0 * s);
      for (Sensor sensor : {Sensor::kAccelerometer, Sensor::kGyro}) {
        const double sigma = sensor == Sensor::kAccelerometer ? kInsSigmaV : kInsSigmaR;
        for (const FaultSpec& spec : standard_faults(sigma)) {
          Case c = voyage_case(voyage);
          c.faulty = true;
          c.fault = InjectedFault{sensor, spec.kind, onset, onset + p.fault_len};
          c.magnitude = spec.magnitude;
          c.duration = onset + p.fault_len + p.tail;
          const FaultInjection fi = to_injection(c.fault, spec.magnitude);
          c.make = [hull = sub.hull, voyage, rate, seed = c.seed, d = c.duration, fi] {
            return voyage_stream(hull, voyage, rate, seed, d, {fi});
          };
          cases->push_back(std::move(c));
        }
      }
    }
  }
}

using Recorded = std::shared_ptr<const std::vector<RecordedRun>>;

/// The README's MMG linearisation (Yasukawa & Yoshimura 2015 at model scale) and B.
/// Each recorded test alone, healthy.
void add_hsva_single_runs(const Recorded& runs, const HsvaModel& mmg, const std::string& table,
                          std::vector<Case>* cases) {
  for (std::size_t i = 0; i < runs->size(); ++i) {
    Case c;
    c.table = table;
    c.note = "each recorded test alone; healthy";
    c.subject = "kvlcc2-hsva";
    c.voyage = (*runs)[i].name;
    c.rate_hz = 20.0;
    c.duration = (*runs)[i].samples.back().t - (*runs)[i].samples.front().t;
    c.B = mmg.B;
    c.A_ref = mmg.A_ref;
    c.make = [runs, i] { return Stream{(*runs)[i].samples, {}}; };
    cases->push_back(std::move(c));
  }
}

/// Fault onsets 30 s into every run of at least 150 s (so that a 60 s fault stays in one
/// run); the quick mode takes the one nearest to 1300 s.
std::vector<double> hsva_fault_onsets(const std::vector<RecordedRun>& runs,
                                      const std::vector<double>& starts, bool quick) {
  std::vector<double> onsets;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const auto& x = runs[i].samples;
    if (x.back().t - x.front().t >= 150.0) onsets.push_back(starts[i] + 30.0);
  }
  if (quick && !onsets.empty()) {
    const double best = *std::min_element(onsets.begin(), onsets.end(), [](double a, double b) {
      return std::abs(a - 1300.0) < std::abs(b - 1300.0);
    });
    onsets = {best};
  }
  return onsets;
}

/// The healthy case of the concatenated tests; the faulty ones are copies of it.
Case hsva_concatenated_case(const std::string& table, const Vec2& noise, const Vec2& sigma,
                            double span, const HsvaModel& mmg) {
  Case base;
  base.table = table;
  char note[256];
  std::snprintf(note, sizeof note,
                "healthy noise of the recordings sigma_v = %.2g m/s, sigma_r = %.2g rad/s; "
                "faults sized with sigma_v = %.2g m/s, sigma_r = %.2g rad/s (at least the "
                "engine's scale floors)",
                noise(0), noise(1), sigma(0), sigma(1));
  base.note = note;
  base.subject = "kvlcc2-hsva";
  base.voyage = "13 runs, 3 s apart";
  base.rate_hz = 20.0;
  base.duration = span;
  base.B = mmg.B;
  base.A_ref = mmg.A_ref;
  return base;
}

/// The recorded tests one after another, healthy, then with each standard fault on each
/// channel at every onset (sized with the recorded noise, at least the engine's floors).
/// Every faulty case takes the next seed of *serial.
void add_hsva_concatenated(const Recorded& runs, const HsvaModel& mmg, const std::string& table,
                           bool quick, std::uint64_t* serial, std::vector<Case>* cases) {
  std::vector<double> starts;
  auto all = std::make_shared<const std::vector<Sample>>(concatenate(*runs, 3.0, &starts));
  const Vec2 noise = recorded_noise(*runs);
  const Vec2 sigma = noise.cwiseMax(fault_sigma_floor());
  const double span = all->back().t - all->front().t;
  const Case base = hsva_concatenated_case(table, noise, sigma, span, mmg);
  {
    Case c = base;
    c.make = [all] { return Stream{*all, {}}; };
    cases->push_back(std::move(c));
  }
  for (double onset : hsva_fault_onsets(*runs, starts, quick)) {
    for (Sensor sensor : {Sensor::kAccelerometer, Sensor::kGyro}) {
      const double sg = sensor == Sensor::kAccelerometer ? sigma(0) : sigma(1);
      for (const FaultSpec& spec : standard_faults(sg)) {
        Case c = base;
        c.seed = mix_seed(++*serial);
        c.faulty = true;
        c.fault = InjectedFault{sensor, spec.kind, onset, onset + 60.0};
        c.magnitude = spec.magnitude;
        c.voyage = base.voyage + ", fault at " + std::to_string(static_cast<int>(onset)) + " s";
        c.make = [all, f = c.fault, m = spec.magnitude, seed = c.seed] {
          Stream st{*all, {f}};
          apply_fault(&st.samples, f, m, seed);
          return st;
        };
        cases->push_back(std::move(c));
      }
    }
  }
}

/// The HSVA KVLCC2 tables: the single runs and the concatenated runs with faults.
void add_hsva_tables(const BenchOptions& opt, std::uint64_t* serial, std::vector<Case>* cases) {
  const Recorded runs =
      std::make_shared<const std::vector<RecordedRun>>(load_hsva(opt.realdata_dir));
  // B as a user gives it (the directory's kvlcc2_model.yaml through the engine's loader), A
  // for the oracle from its README.
  const HsvaModel mmg = load_hsva_model(opt.realdata_dir);
  const std::string single = "kvlcc2-hsva single runs @ 20 Hz";
  if (wanted(opt, single)) add_hsva_single_runs(runs, mmg, single, cases);
  const std::string concat = "kvlcc2-hsva concatenated @ 20 Hz";
  if (wanted(opt, concat)) add_hsva_concatenated(runs, mmg, concat, opt.quick, serial, cases);
}

/// B only, as a user without a speed log gives it: the samples' u is dropped.
void drop_speed(std::vector<Case>* cases) {
  for (Case& c : *cases) {
    c.make = [make = std::move(c.make)] {
      Stream st = make();
      for (Sample& x : st.samples) x.u = kNaN;
      return st;
    };
  }
}

}  // namespace

std::vector<Case> make_cases(const BenchOptions& opt) {
  const Plan p = plan_of(opt);
  std::vector<Case> cases;
  std::uint64_t serial = 0;
  for (const Subject& sub : zoo_subjects()) {
    for (double rate : p.rates) {
      const std::string table = sub.name + " @ " + rate_name(rate);
      if (wanted(opt, table)) add_zoo_table(sub, rate, p, table, &serial, &cases);
    }
  }
  if (!opt.realdata_dir.empty()) add_hsva_tables(opt, &serial, &cases);
  if (!opt.speed) drop_speed(&cases);
  return cases;
}

CaseResult run_case(const Case& c, std::size_t index, const EngineConfig& engine_cfg,
                    const EngineConfig& paper_cfg, const ScoreParams& score) {
  const Stream st = c.make();
  CaseResult out;
  out.index = index;
  out.samples = st.samples.size();
  if (st.samples.empty()) throw std::runtime_error(c.table + " / " + c.voyage + ": no samples");
  out.t_first = st.samples.front().t;
  out.t_last = st.samples.back().t;
  EngineConfig ec = engine_cfg;
  ec.B = c.B;
  EngineConfig pc = paper_cfg;
  pc.B = c.B;
  out.m[kEngine] = run_engine(ec, st.samples);
  out.m[kPaper] = run_engine(pc, st.samples);
  out.m[kOracle] = run_oracle(engine_cfg.isolation, c.B, c.A_ref, st.samples);
  for (MethodResult& m : out.m) {
    m.score = score_run(st.faults, m.alarms, out.t_first, out.t_last, m.live, score);
  }
  return out;
}

namespace {

/// The table of that name, appended (with empty per-kind counts) when it is new.
TableSummary& table_named(std::vector<TableSummary>* tables, const std::string& name) {
  for (TableSummary& t : *tables) {
    if (t.name == name) return t;
  }
  tables->push_back(TableSummary{});
  tables->back().name = name;
  for (MethodSummary& m : tables->back().m) {
    m.per_kind.assign(standard_kinds().size(), {0, 0, 0});
  }
  return tables->back();
}

/// The values of one method over one table whose quantiles the summary reports.
struct Acc {
  std::vector<double> delay, recovery, arming, a_error;
};

/// The scores of a run's faults: counts overall and per standard kind, delays, recoveries.
void add_fault_scores(const std::vector<FaultScore>& faults, MethodSummary* m, Acc* a) {
  for (const FaultScore& f : faults) {
    ++m->faults;
    const auto& kinds = standard_kinds();
    const std::size_t kind = static_cast<std::size_t>(
        std::find(kinds.begin(), kinds.end(), f.fault.kind) - kinds.begin());
    if (kind < kinds.size()) ++m->per_kind[kind][0];
    if (f.armed_at_onset) ++m->armed_at_onset;
    if (!f.detected) continue;
    ++m->detected;
    if (f.armed_at_onset) ++m->detected_armed;
    if (kind < kinds.size()) ++m->per_kind[kind][1];
    if (f.isolated) {
      ++m->isolated;
      if (kind < kinds.size()) ++m->per_kind[kind][2];
    }
    a->delay.push_back(f.delay);
    if (f.held) ++m->held;
    if (f.recovered) {
      ++m->recovered;
      a->recovery.push_back(f.recovery_delay);
    }
  }
}

/// One method's result on one run of case c: arming, the error of A, false alarms, healthy
/// hours and the faults' scores.
void add_method_run(const Case& c, const CaseResult& r, const MethodResult& mr, MethodSummary* m,
                    Acc* a) {
  ++m->runs;
  if (std::isfinite(mr.t_armed)) {
    ++m->armed_runs;
    a->arming.push_back(mr.t_armed - r.t_first);
  }
  const double ref = c.A_ref.norm();
  a->a_error.push_back(ref > 0 ? (mr.A_final - c.A_ref).norm() / ref : kNaN);
  m->false_alarms += static_cast<int>(mr.score.false_alarms());
  for (double tf : mr.score.false_alarm_times) {
    if (live_at(mr.live, tf)) ++m->false_alarms_armed;
  }
  m->healthy_hours += mr.score.healthy_time / 3600.0;
  m->healthy_armed_hours += mr.score.healthy_armed_time / 3600.0;
  m->has_identification = mr.has_identification;
  if (!c.faulty) {
    m->healthy_run_hours += (r.t_last - r.t_first) / 3600.0;
    m->healthy_run_mismatches += static_cast<int>(mr.mismatches.size());
    m->healthy_run_samples += mr.samples;
    m->healthy_run_frozen += mr.frozen_samples;
  }
  add_fault_scores(mr.score.faults, m, a);
}

void set_quantiles(const Acc& a, MethodSummary* m) {
  m->delay_median = quantile(a.delay, 0.5);
  m->delay_p95 = quantile(a.delay, 0.95);
  m->recovery_median = quantile(a.recovery, 0.5);
  m->recovery_p95 = quantile(a.recovery, 0.95);
  m->arming_median = quantile(a.arming, 0.5);
  m->arming_max = quantile(a.arming, 1.0);
  m->a_error_median = quantile(a.a_error, 0.5);
  m->a_error_p95 = quantile(a.a_error, 0.95);
}

}  // namespace

std::vector<TableSummary> summarise(const std::vector<Case>& cases,
                                    const std::vector<CaseResult>& results) {
  std::vector<TableSummary> tables;
  std::vector<std::array<Acc, kMethods>> acc;
  for (const CaseResult& r : results) {
    const Case& c = cases[r.index];
    TableSummary& t = table_named(&tables, c.table);
    const std::size_t ti = static_cast<std::size_t>(&t - tables.data());
    if (acc.size() <= ti) acc.resize(ti + 1);
    ++t.runs;
    if (t.note.empty()) t.note = c.note;
    t.hours += (r.t_last - r.t_first) / 3600.0;
    for (int k = 0; k < kMethods; ++k) add_method_run(c, r, r.m[k], &t.m[k], &acc[ti][k]);
  }
  for (std::size_t ti = 0; ti < tables.size(); ++ti) {
    for (int k = 0; k < kMethods; ++k) set_quantiles(acc[ti][k], &tables[ti].m[k]);
  }
  return tables;
}

void load_configs(const std::string& config_dir, EngineConfig* engine, EngineConfig* paper) {
  *engine = io::load_engine_config(config_dir + "/default.yaml");
  *paper = io::load_engine_config(config_dir + "/paper.yaml");
}

std::vector<CaseResult> run_all(const std::vector<Case>& cases, const BenchOptions& opt,
                                const EngineConfig& engine_cfg, const EngineConfig& paper_cfg) {
  std::vector<CaseResult> results(cases.size());
  std::atomic<std::size_t> next{0}, done{0};
  std::atomic<double> data_hours{0.0};
  std::mutex mu;
  std::condition_variable cv;
  std::string error;
  double total_hours = 0.0;
  for (const Case& c : cases) total_hours += c.duration / 3600.0;
  const auto t0 = std::chrono::steady_clock::now();
  auto worker = [&] {
    for (;;) {
      const std::size_t i = next.fetch_add(1);
      if (i >= cases.size()) return;
      {
        std::lock_guard<std::mutex> lock(mu);
        if (!error.empty()) return;
      }
      try {
        results[i] = run_case(cases[i], i, engine_cfg, paper_cfg, opt.score);
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(mu);
        if (error.empty()) error = cases[i].table + " / " + cases[i].voyage + ": " + e.what();
      }
      double h = data_hours.load();
      while (!data_hours.compare_exchange_weak(h, h + cases[i].duration / 3600.0)) {
      }
      ++done;
      cv.notify_all();
    }
  };
  const int jobs = std::max(1, opt.jobs);
  std::vector<std::thread> pool;
  for (int j = 0; j < jobs; ++j) pool.emplace_back(worker);
  const bool tty = isatty(STDERR_FILENO) != 0;
  {
    std::unique_lock<std::mutex> lock(mu);
    auto last = std::chrono::steady_clock::now();
    while (done.load() < cases.size() && error.empty()) {
      cv.wait_for(lock, std::chrono::seconds(1));
      const auto now = std::chrono::steady_clock::now();
      const double since = std::chrono::duration<double>(now - last).count();
      if (!opt.progress || since < (tty ? 1.0 : 30.0)) continue;
      last = now;
      const double el = std::chrono::duration<double>(now - t0).count();
      const double h = data_hours.load();
      const double eta = h > 0 ? el * (total_hours - h) / h : 0.0;
      std::fprintf(
          stderr,
          "%sbench detection: %zu/%zu runs, %.1f/%.1f h of data, %.0f s elapsed, ~%.0f s left%s",
          tty ? "\r" : "", done.load(), cases.size(), h, total_hours, el, eta, tty ? "   " : "\n");
      std::fflush(stderr);
    }
  }
  for (std::thread& t : pool) t.join();
  if (opt.progress && tty) std::fprintf(stderr, "\n");
  if (!error.empty()) throw std::runtime_error(error);
  return results;
}

}  // namespace usvfdi::bench
