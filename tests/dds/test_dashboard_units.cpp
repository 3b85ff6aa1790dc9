// Units of usv-fdi dashboard with no DDS and no HTTP in them (src/app/dashboard/board.cpp): the
// IEC 62923 presentation, the event history, the board's JSON, the acknowledgement request's
// checks and the Prometheus text. The page itself is tested in a real browser (tests/dashboard).
#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "dashboard/board.hpp"
#include "dashboard/metrics.hpp"
#include "dashboard/vessel_history.hpp"

namespace usvfdi::app::dashboard {
namespace {

Row row(std::uint32_t mmsi, Sensor s, FaultState st, std::uint64_t seq, double written = 100.0) {
  Row r;
  r.mmsi = mmsi;
  r.ev.sensor = s;
  r.ev.state = st;
  r.ev.kind = FaultKind::kBias;
  r.ev.sequence = seq;
  r.ev.c_a = 0.1;
  r.ev.c_g = 0.9;
  r.written = written;
  return r;
}

TEST(DashboardBoard, EveryLatchedStateHasItsIec62923Presentation) {
  EXPECT_STREQ(presentation(FaultState::kRaised), "active-unacknowledged");
  EXPECT_STREQ(presentation(FaultState::kActiveAcknowledged), "active-acknowledged");
  EXPECT_STREQ(presentation(FaultState::kClearedUnacknowledged), "rectified-unacknowledged");
  EXPECT_STREQ(presentation(FaultState::kAcknowledged), "normal");
  EXPECT_STREQ(presentation(FaultState::kNormal), "normal");
}

TEST(DashboardBoard, TheHistoryIsNewestFirstBoundedAndSkipsRepeats) {
  EventHistory h(3);
  h.add(row(1, Sensor::kGyro, FaultState::kRaised, 1));
  h.add(row(1, Sensor::kGyro, FaultState::kRaised, 1));  // a late joiner's copy: not again
  h.add(row(1, Sensor::kGyro, FaultState::kClearedUnacknowledged, 2));
  h.add(row(2, Sensor::kAccelerometer, FaultState::kRaised, 1));
  EXPECT_EQ(h.size(), 3u);
  h.add(row(1, Sensor::kGyro, FaultState::kAcknowledged, 3));
  ASSERT_EQ(h.size(), 3u);  // the oldest went
  const auto j = h.to_json(200.0);
  EXPECT_EQ(j[0]["sequence"], 3);
  EXPECT_EQ(j[1]["mmsi"], 2);
  EXPECT_EQ(j[2]["sequence"], 2);
  EXPECT_DOUBLE_EQ(j[0]["age_s"].get<double>(), 100.0);
}

TEST(DashboardBoard, TheBoardHasEveryVesselHeardLatchedOrOnTheRoster) {
  BoardInput in;
  in.rows[{7, static_cast<int>(Sensor::kGyro)}] = row(7, Sensor::kGyro, FaultState::kRaised, 1);
  in.heard_age[7] = 0.5;
  in.silent[7] = false;
  in.heard_age[8] = 9.0;  // heard, silent, nothing latched
  in.silent[8] = true;
  in.roster_never_heard = {9};
  Row nan = row(7, Sensor::kAccelerometer, FaultState::kClearedUnacknowledged, 2);
  nan.ev.c_a = std::numeric_limits<double>::quiet_NaN();
  in.rows[{7, static_cast<int>(Sensor::kAccelerometer)}] = nan;
  EventHistory h;
  std::deque<AckOutcome> acks(1);
  acks[0].mmsi = 7;
  acks[0].sensor = Sensor::kGyro;
  acks[0].sequence = 1;
  acks[0].operator_id = "alice";
  acks[0].state = "refused";
  acks[0].reason = "stale sequence";
  const auto j = board_json(in, h, acks, 101.0);
  ASSERT_EQ(j["vessels"].size(), 3u);
  const auto& v7 = j["vessels"][0];
  EXPECT_EQ(v7["mmsi"], 7);
  EXPECT_EQ(v7["sensors"]["gyro"]["presentation"], "active-unacknowledged");
  EXPECT_EQ(v7["sensors"]["gyro"]["state"], "raised");
  EXPECT_TRUE(v7["sensors"]["accelerometer"]["c_a"].is_null()) << "NaN is null, not invalid JSON";
  EXPECT_TRUE(v7["status"].is_null());
  EXPECT_FALSE(v7["silent"].get<bool>());
  EXPECT_TRUE(j["vessels"][1]["silent"].get<bool>());
  EXPECT_TRUE(j["vessels"][2]["never_heard"].get<bool>());
  EXPECT_TRUE(j["vessels"][2]["heard_age_s"].is_null());
  EXPECT_EQ(j["acks"][0]["reason"], "stale sequence");
  EXPECT_NO_THROW(nlohmann::json::parse(j.dump()));
}

/// What the page does with a delta (applyDelta in web/app.js), in C++: only the next revision.
nlohmann::json apply_delta(nlohmann::json board, const nlohmann::json& d) {
  EXPECT_EQ(d["revision"].get<std::uint64_t>(), board["revision"].get<std::uint64_t>() + 1)
      << "a page takes only the delta after its board";
  std::map<std::uint32_t, nlohmann::json> vessels;
  for (const auto& v : board["vessels"]) vessels[v["mmsi"].get<std::uint32_t>()] = v;
  for (const auto& m : d["removed"]) vessels.erase(m.get<std::uint32_t>());
  for (const auto& v : d["vessels"]) vessels[v["mmsi"].get<std::uint32_t>()] = v;
  if (d.contains("status_numbers")) {
    for (const auto& [m, nums] : d["status_numbers"].items()) {
      for (const auto& [k, x] : nums.items()) vessels[std::stoul(m)]["status"][k] = x;
    }
  }
  board["vessels"] = nlohmann::json::array();
  for (auto& [m, v] : vessels) {
    const std::string key = std::to_string(m);
    if (d["heard_age"].contains(key)) v["heard_age_s"] = d["heard_age"][key];
    for (auto& [s, r] : v["sensors"].items()) {
      r["age_s"] = d["now"].get<double>() - r["written"].get<double>();
    }
    board["vessels"].push_back(v);
  }
  nlohmann::json events = d["events"];
  for (const auto& e : board["events"]) events.push_back(e);
  while (events.size() > d["event_capacity"].get<std::size_t>()) events.erase(events.size() - 1);
  board["events"] = events;
  for (const char* k : {"now", "silent_after", "conflicts", "acks", "can_ack", "revision"}) {
    board[k] = d[k];
  }
  return board;
}

/// The board without the events' ages (the page does not show them, and a delta does not move
/// them on).
nlohmann::json without_event_ages(nlohmann::json j) {
  for (auto& e : j["events"]) e.erase("age_s");
  return j;
}

/// board_json and the can_ack and revision the framer's boards carry.
nlohmann::json board_json_with_can_ack(const BoardInput& in, const EventHistory& h,
                                       const std::deque<AckOutcome>& acks, double now,
                                       std::uint64_t revision) {
  nlohmann::json j = board_json(in, h, acks, now);
  j["can_ack"] = true;
  j["revision"] = revision;
  return j;
}

TEST(DashboardBoard, DeltasCarryOnlyWhatChangedAndApplyToTheNextBoard) {
  BoardFramer framer;
  EventHistory h(3);
  std::deque<AckOutcome> acks;
  BoardInput in;
  for (std::uint32_t m = 1; m <= 4; ++m) {
    in.heard_age[m] = 0.1 * m;
    in.silent[m] = false;
  }
  const Row g1 = row(2, Sensor::kGyro, FaultState::kRaised, 1, 90.0);
  in.rows[{2, static_cast<int>(Sensor::kGyro)}] = g1;
  h.add(g1);
  // GIVEN a first frame: the whole board, and a delta that carries every vessel
  BoardFrame f = framer.frame(in, h, acks, 100.0, true);
  nlohmann::json board = nlohmann::json::parse(f.full);
  nlohmann::json d = nlohmann::json::parse(f.delta);
  EXPECT_EQ(board["vessels"].size(), 4u);
  EXPECT_TRUE(board["can_ack"].get<bool>());
  EXPECT_EQ(d["vessels"].size(), 4u);
  EXPECT_EQ(d["events"].size(), 1u);
  // AND both are revision 1 (the whole board is as of the last delta)
  EXPECT_EQ(d["revision"], 1);
  EXPECT_EQ(board["revision"], 1);
  // WHEN only time passes (every vessel heard again, nothing latched changes)
  for (std::uint32_t m = 1; m <= 4; ++m) in.heard_age[m] = 0.2 * m;
  f = framer.frame(in, h, acks, 101.0, true);
  d = nlohmann::json::parse(f.delta);
  // THEN the delta carries no vessel and no event, only the ages, as revision 2
  EXPECT_EQ(d["revision"], 2);
  EXPECT_EQ(d["vessels"].size(), 0u) << d.dump();
  EXPECT_EQ(d["events"].size(), 0u);
  EXPECT_DOUBLE_EQ(d["heard_age"]["3"].get<double>(), 0.6);
  EXPECT_LT(f.delta.size(), f.full.size() / 3);
  board = apply_delta(board, d);
  EXPECT_EQ(without_event_ages(board), without_event_ages(nlohmann::json::parse(f.full)));
  // WHEN vessel 3 raises, vessel 2's fault clears, vessel 4 leaves the board and 5 joins, with
  //   three events (one more than the history's capacity of 3 holds with the one before)
  const Row a3 = row(3, Sensor::kAccelerometer, FaultState::kRaised, 1, 100.5);
  const Row g2 = row(2, Sensor::kGyro, FaultState::kClearedUnacknowledged, 2, 100.6);
  const Row g5 = row(5, Sensor::kGyro, FaultState::kRaised, 1, 100.7);
  in.rows[{3, static_cast<int>(Sensor::kAccelerometer)}] = a3;
  in.rows[{2, static_cast<int>(Sensor::kGyro)}] = g2;
  in.rows[{5, static_cast<int>(Sensor::kGyro)}] = g5;
  in.heard_age.erase(4);
  in.silent.erase(4);
  in.heard_age[5] = 0.0;
  in.silent[5] = false;
  for (const Row& r : {a3, g2, g5}) h.add(r);
  acks.push_back(AckOutcome{2, Sensor::kGyro, 1, "alice", 100.2, "accepted", ""});
  f = framer.frame(in, h, acks, 102.0, true);
  d = nlohmann::json::parse(f.delta);
  // THEN the delta carries vessels 2, 3 and 5 whole, 4 as removed, the three events newest
  //   first, and the acknowledgements
  std::vector<std::uint32_t> carried;
  for (const auto& v : d["vessels"]) carried.push_back(v["mmsi"].get<std::uint32_t>());
  EXPECT_EQ(carried, (std::vector<std::uint32_t>{2, 3, 5}));
  EXPECT_EQ(d["removed"], nlohmann::json::array({4}));
  ASSERT_EQ(d["events"].size(), 3u);
  EXPECT_EQ(d["events"][0]["mmsi"], 5);
  EXPECT_EQ(d["events"][2]["mmsi"], 3);
  EXPECT_EQ(d["acks"][0]["operator"], "alice");
  // AND applied to the page's board it gives the whole board of this frame
  board = apply_delta(board, d);
  EXPECT_EQ(without_event_ages(board), without_event_ages(nlohmann::json::parse(f.full)))
      << board.dump() << "\n"
      << f.full;
}

TEST(DashboardBoard, ADeltaRebuildsOnlyTheVesselsThatChanged) {
  // GIVEN a fleet of 1000 vessels, each with a status, framed once
  BoardFramer framer;
  EventHistory h;
  std::deque<AckOutcome> acks;
  BoardInput in;
  for (std::uint32_t m = 1; m <= 1000; ++m) {
    in.heard_age[m] = 0.5;
    in.silent[m] = false;
    in.statuses[m].written = 50.0;
    in.statuses[m].st.mmsi(m);
  }
  EXPECT_EQ(
      nlohmann::json::parse(framer.delta(in, nullptr, h, acks, 100.0, true))["vessels"].size(),
      1000u);
  EXPECT_EQ(framer.rebuilt(), 1000u);
  nlohmann::json board = nlohmann::json::parse(framer.full(in, h, acks, 100.0, true));
  // WHEN vessel 7 raises (its row touched), vessel 9's status moves on and vessel 3 falls silent
  const Row g7 = row(7, Sensor::kGyro, FaultState::kRaised, 1, 100.5);
  in.rows[{7, static_cast<int>(Sensor::kGyro)}] = g7;
  h.add(g7);
  in.statuses[9].st.armed(true);
  in.statuses[9].written = 51.0;
  in.silent[3] = true;
  // (and vessel 10's next status, which says nothing new: only its numbers move on)
  in.statuses[10].written = 51.0;
  in.statuses[10].st.samples(500);
  const std::set<std::uint32_t> touched{7, 9, 10};
  const nlohmann::json d = nlohmann::json::parse(framer.delta(in, &touched, h, acks, 101.0, true));
  // THEN only those four entries were built again, the delta carries three of them whole and
  // vessel 10's status numbers apart
  EXPECT_EQ(framer.rebuilt(), 4u);
  ASSERT_TRUE(d["status_numbers"].contains("10")) << d["status_numbers"].dump();
  EXPECT_EQ(d["status_numbers"].size(), 1u);
  EXPECT_EQ(d["status_numbers"]["10"]["samples"], 500);
  EXPECT_DOUBLE_EQ(d["status_numbers"]["10"]["written"].get<double>(), 51.0);
  std::vector<std::uint32_t> carried;
  for (const auto& v : d["vessels"]) carried.push_back(v["mmsi"].get<std::uint32_t>());
  EXPECT_EQ(carried, (std::vector<std::uint32_t>{3, 7, 9}));
  EXPECT_EQ(d["vessels"][1]["sensors"]["gyro"]["state"], "raised");
  EXPECT_DOUBLE_EQ(d["vessels"][1]["sensors"]["gyro"]["age_s"].get<double>(), 0.5);
  EXPECT_TRUE(d["vessels"][2]["status"]["armed"].get<bool>());
  // AND the whole board built on demand is the one the deltas put together
  const nlohmann::json full = nlohmann::json::parse(framer.full(in, h, acks, 101.0, true));
  EXPECT_EQ(without_event_ages(apply_delta(board, d)), without_event_ages(full));
  EXPECT_EQ(full, board_json_with_can_ack(in, h, acks, 101.0, 2));
  // WHEN nothing is touched, THEN nothing is built again
  framer.delta(in, &touched, h, acks, 102.0, true);
  EXPECT_EQ(framer.rebuilt(), 3u) << "the touched ones, found unchanged";
  framer.delta(in, nullptr, h, acks, 102.0, true);
  EXPECT_EQ(framer.rebuilt(), 1000u);
  const std::set<std::uint32_t> none;
  const nlohmann::json quiet = nlohmann::json::parse(framer.delta(in, &none, h, acks, 103.0, true));
  EXPECT_EQ(framer.rebuilt(), 0u);
  EXPECT_TRUE(quiet["vessels"].empty());
}

TEST(DashboardMetrics, TheFleetIsExposedInPrometheusTextForm) {
  BoardInput in;
  in.rows[{7, static_cast<int>(Sensor::kGyro)}] = row(7, Sensor::kGyro, FaultState::kRaised, 3);
  in.rows[{7, static_cast<int>(Sensor::kAccelerometer)}] =
      row(7, Sensor::kAccelerometer, FaultState::kClearedUnacknowledged, 2);
  in.rows[{8, static_cast<int>(Sensor::kGyro)}] =
      row(8, Sensor::kGyro, FaultState::kActiveAcknowledged, 5);
  in.heard_age[7] = 0.5;
  in.silent[7] = false;
  in.heard_age[8] = 9.0;
  in.silent[8] = true;
  in.roster_never_heard = {9};
  in.statuses[7].st.converged(true);
  in.statuses[7].st.armed(false);
  in.conflicts = 1;
  // The sidecar's sequence of one instance: raised, its kind refined (the same raise, next
  // sequence), acknowledged, cleared, raised again; and a raise whose clearing was not seen.
  EventHistory h;
  const auto ev = [](FaultState st, std::uint64_t seq, double detected, FaultKind kind) {
    Row r = row(7, Sensor::kGyro, st, seq);
    r.ev.detection_time = detected;
    r.ev.kind = kind;
    return r;
  };
  h.add(ev(FaultState::kRaised, 1, 10.0, FaultKind::kBias));
  h.add(ev(FaultState::kRaised, 1, 10.0, FaultKind::kBias));   // a repeat
  h.add(ev(FaultState::kRaised, 2, 10.0, FaultKind::kDrift));  // refined: no new raise
  EXPECT_EQ(h.raises().at({7, static_cast<int>(Sensor::kGyro)}), 1u);
  h.add(ev(FaultState::kActiveAcknowledged, 3, 10.0, FaultKind::kDrift));
  h.add(ev(FaultState::kAcknowledged, 4, 10.0, FaultKind::kDrift));
  h.add(ev(FaultState::kRaised, 5, 50.0, FaultKind::kBias));  // raised again
  EXPECT_EQ(h.raises().at({7, static_cast<int>(Sensor::kGyro)}), 2u);
  h.add(ev(FaultState::kRaised, 8, 90.0, FaultKind::kBias));  // 6, 7 (its clearing) not seen
  EXPECT_EQ(h.raises().at({7, static_cast<int>(Sensor::kGyro)}), 3u);
  std::deque<AckOutcome> acks(2);
  acks[0].state = "accepted";
  acks[1].state = "refused";
  const std::string t = fleet_metrics(in, h, acks);
  const auto has = [&t](const std::string& line) {
    return t.find("\n" + line + "\n") != std::string::npos;
  };
  EXPECT_NE(t.find("# TYPE usv_fdi_fleet_raises_total counter"), std::string::npos) << t;
  EXPECT_TRUE(has("usv_fdi_fleet_vessels 3")) << t;
  EXPECT_TRUE(has("usv_fdi_fleet_silent{mmsi=\"7\"} 0")) << t;
  EXPECT_TRUE(has("usv_fdi_fleet_silent{mmsi=\"8\"} 1")) << t;
  EXPECT_TRUE(has("usv_fdi_fleet_silent{mmsi=\"9\"} 1")) << t;
  EXPECT_TRUE(has("usv_fdi_fleet_heard_age_seconds{mmsi=\"9\"} +Inf")) << t;
  EXPECT_TRUE(has("usv_fdi_fleet_fault_active{mmsi=\"7\",sensor=\"gyro\"} 1")) << t;
  EXPECT_TRUE(has("usv_fdi_fleet_fault_active{mmsi=\"7\",sensor=\"accelerometer\"} 0")) << t;
  EXPECT_TRUE(has("usv_fdi_fleet_fault_unacknowledged{mmsi=\"7\",sensor=\"accelerometer\"} 1"))
      << t;
  EXPECT_TRUE(has("usv_fdi_fleet_fault_active{mmsi=\"8\",sensor=\"gyro\"} 1")) << t;
  EXPECT_TRUE(has("usv_fdi_fleet_fault_unacknowledged{mmsi=\"8\",sensor=\"gyro\"} 0")) << t;
  EXPECT_TRUE(has("usv_fdi_fleet_raises_total{mmsi=\"7\",sensor=\"gyro\"} 3")) << t;
  EXPECT_TRUE(has("usv_fdi_fleet_converged{mmsi=\"7\"} 1")) << t;
  EXPECT_TRUE(has("usv_fdi_fleet_armed{mmsi=\"7\"} 0")) << t;
  EXPECT_TRUE(has("usv_fdi_fleet_writer_conflicts_total 1")) << t;
  EXPECT_TRUE(has("usv_fdi_dashboard_acks{state=\"accepted\"} 1")) << t;
  EXPECT_TRUE(has("usv_fdi_dashboard_acks{state=\"pending\"} 0")) << t;
}

TEST(DashboardBoard, APeersTextIsEscapedSoTheBoardIsAlwaysValidJson) {
  // A message cut inside a multi-byte character, or a peer's bytes: never raw in the JSON.
  Row r = row(7, Sensor::kGyro, FaultState::kRaised, 1);
  r.ev.message = "bias \xe2\x82 \xff\x1b[31m";
  EventHistory h;
  h.add(r);
  BoardInput in;
  in.rows[{7, static_cast<int>(Sensor::kGyro)}] = r;
  const auto j = board_json(in, h, {}, 101.0);
  std::string text;
  ASSERT_NO_THROW(text = j.dump());
  EXPECT_EQ(j["events"][0]["message"], "bias \\xe2\\x82 \\xff\\x1b[31m");
  EXPECT_EQ(text.find('\x1b'), std::string::npos);
}

TEST(DashboardBoard, TheSidecarsRecordOfAnAckNamesTheOperatorWithOrWithoutItsIdentity) {
  EXPECT_TRUE(acknowledged_by("acknowledged by carol", "carol"));
  // under DDS Security: the writer's authenticated CN, then the name it claimed
  EXPECT_TRUE(acknowledged_by("acknowledged by dashboard:carol", "carol"));
  EXPECT_FALSE(acknowledged_by("acknowledged by dashboard:carola", "carol"));
  EXPECT_FALSE(acknowledged_by("acknowledged by carola", "carol"));
  EXPECT_FALSE(acknowledged_by("acknowledged by :carol", "carol"));
  EXPECT_FALSE(acknowledged_by("acknowledged by dashboard:carol", ""));
  EXPECT_FALSE(acknowledged_by("residual back below 3.0", "carol"));
}

TEST(DashboardVesselHistory, AVesselsStatusesAreKeptAsChartColumnsBoundedAndInTimeOrder) {
  VesselHistory h(3);
  const auto status = [](std::uint32_t mmsi, double written, double jg) {
    VesselStatus v;
    v.st.mmsi(mmsi);
    v.written = written;
    v.st.j_peak({std::numeric_limits<double>::quiet_NaN(), jg});
    v.st.j_raise({6.0, 6.5});
    v.st.j_leave({3.0, 3.25});
    v.st.c_g(0.3);
    v.st.a({-1.0, 0.5, 0.25, -2.0});
    v.st.armed(true);
    return v;
  };
  nlohmann::json j;
  EXPECT_FALSE(h.to_json(7, 0.0, &j));
  h.add(status(7, 10.0, 1.0));
  h.add(status(7, 10.0, 9.0));  // a repeat of the same time: not again
  h.add(status(7, 9.0, 9.0));   // older: not added
  h.add(status(8, 10.5, 2.0));  // another vessel
  h.add(status(7, 11.0, 2.0));
  h.add(status(7, 12.0, 7.5));
  h.add(status(7, 13.0, 3.0));  // the fourth point of vessel 7: the first goes
  ASSERT_TRUE(h.to_json(7, 0.0, &j));
  EXPECT_EQ(j["mmsi"], 7);
  EXPECT_EQ(j["capacity"], 3);
  EXPECT_EQ(j["t"], nlohmann::json({11.0, 12.0, 13.0}));
  EXPECT_EQ(j["j_g"], nlohmann::json({2.0, 7.5, 3.0}));
  EXPECT_EQ(j["j_a"], nlohmann::json({nullptr, nullptr, nullptr})) << "NaN is null";
  EXPECT_EQ(j["raise_g"][0], 6.5);
  EXPECT_EQ(j["leave_g"][0], 3.25);
  EXPECT_EQ(j["c_g"][0], 0.3) << "a float sent in its shortest form";
  EXPECT_EQ(j["a12"][2], 0.5);
  EXPECT_EQ(j["a22"][2], -2.0);
  EXPECT_EQ(j["armed"][1], 1.0);
  for (const char* k : VesselHistory::kSeries) EXPECT_EQ(j[k].size(), 3u) << k;
  ASSERT_TRUE(h.to_json(7, 12.0, &j));  // only what is newer than the last point shown
  EXPECT_EQ(j["t"], nlohmann::json({13.0}));
  EXPECT_EQ(h.vessels(), 2u);
}

TEST(DashboardBoard, AnAckRequestIsCheckedFieldByField) {
  AckWork w;
  std::string why;
  ASSERT_TRUE(parse_ack_body(R"({"mmsi":257000001,"sensor":"gyro","sequence":3,"operator":"al"})",
                             &w, &why))
      << why;
  EXPECT_EQ(w.req.mmsi, 257000001u);
  EXPECT_EQ(w.req.sensor, Sensor::kGyro);
  EXPECT_EQ(w.req.sequence, 3u);
  EXPECT_EQ(w.operator_id, "al");
  const auto refused = [&](const std::string& body, const std::string& named) {
    AckWork x;
    std::string y;
    EXPECT_FALSE(parse_ack_body(body, &x, &y)) << body;
    EXPECT_NE(y.find(named), std::string::npos) << body << " -> " << y;
  };
  refused("not json", "not JSON");
  refused("[1,2]", "object");
  refused(R"({"sensor":"gyro","sequence":3,"operator":"a"})", "mmsi");
  refused(R"({"mmsi":0,"sensor":"gyro","sequence":3,"operator":"a"})", "mmsi");
  refused(R"({"mmsi":1000000000,"sensor":"gyro","sequence":3,"operator":"a"})", "mmsi");
  refused(R"({"mmsi":-5,"sensor":"gyro","sequence":3,"operator":"a"})", "mmsi");
  refused(R"({"mmsi":"257","sensor":"gyro","sequence":3,"operator":"a"})", "mmsi");
  refused(R"({"mmsi":1,"sensor":"compass","sequence":3,"operator":"a"})", "sensor");
  refused(R"({"mmsi":1,"sensor":"gyro","sequence":0,"operator":"a"})", "sequence");
  refused(R"({"mmsi":1,"sensor":"gyro","sequence":2.5,"operator":"a"})", "sequence");
  refused(R"({"mmsi":1,"sensor":"gyro","sequence":3})", "operator");
  refused(R"({"mmsi":1,"sensor":"gyro","sequence":3,"operator":""})", "operator");
  refused(R"({"mmsi":1,"sensor":"gyro","sequence":3,"operator":")" + std::string(64, 'x') + R"("})",
          "operator");
  refused(R"({"mmsi":1,"sensor":"gyro","sequence":3,"operator":"a\nb"})", "control");
}

}  // namespace
}  // namespace usvfdi::app::dashboard
