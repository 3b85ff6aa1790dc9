// The monitor's units without DDS (issue 9, item 7): the ack protocol and the formatting. (The
// fleet view's logic is InstanceOwners and VesselLiveness, tested in their own files.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "ack_protocol.hpp"
#include "discovery_limit.hpp"
#include "io/json_lite.hpp"
#include "latched_wait.hpp"
#include "monitor_format.hpp"
#include "roster.hpp"
#include "table_output.hpp"

namespace usvfdi::app {
namespace {

namespace js = usvfdi::testing_json;

Row row(FaultState state, std::uint64_t seq, const std::string& message = "residual") {
  Row r;
  r.mmsi = 257000001;
  r.ev.sensor = Sensor::kGyro;
  r.ev.state = state;
  r.ev.kind = FaultKind::kBias;
  r.ev.sequence = seq;
  r.ev.c_g = 1.0;
  r.ev.t = 41.4;
  r.ev.message = message;
  r.written = 1000.0;
  r.writer = "w1";
  return r;
}

TEST(AckProtocol, ParsesTheSpecAndNamesWhatIsWrong) {
  AckRequest a;
  std::string why;
  ASSERT_TRUE(parse_ack("257000001:gyro:3", &a, &why)) << why;
  EXPECT_EQ(a.mmsi, 257000001u);
  EXPECT_EQ(a.sensor, Sensor::kGyro);
  EXPECT_EQ(a.sequence, 3u);
  EXPECT_FALSE(parse_ack("257000001:gyro", &a, &why));
  EXPECT_NE(why.find("expected MMSI:SENSOR:SEQUENCE"), std::string::npos) << why;
  EXPECT_FALSE(parse_ack("257000001:compass:3", &a, &why));
  EXPECT_NE(why.find("sensor 'compass'"), std::string::npos) << why;
  EXPECT_FALSE(parse_ack("257000001:gyro:0", &a, &why));
  EXPECT_FALSE(parse_ack("1000000000:gyro:1", &a, &why));
  EXPECT_FALSE(parse_ack("25700000x:gyro:1", &a, &why));
  EXPECT_NE(why.find("must be integers"), std::string::npos) << why;
}

TEST(AckProtocol, ConfirmedOnlyWhenTheInstanceMovesPastToAnAcknowledgedState) {
  AckRequest a{257000001, Sensor::kGyro, 2};
  const Row cleared = row(FaultState::kClearedUnacknowledged, 2);
  const Row acked = row(FaultState::kAcknowledged, 3);
  const Row raised_again = row(FaultState::kRaised, 3);
  EXPECT_FALSE(ack_confirmed(a, nullptr));
  EXPECT_FALSE(ack_confirmed(a, &cleared));
  EXPECT_TRUE(ack_confirmed(a, &acked));
  EXPECT_FALSE(ack_confirmed(a, &raised_again));
  EXPECT_TRUE(ack_already_past(a, &raised_again));
  EXPECT_FALSE(ack_already_past(a, &cleared));
}

TEST(AckProtocol, TheRefusalReasonFromTheLatchedState) {
  EXPECT_EQ(refusal_reason({1, Sensor::kGyro, 2}, nullptr),
            "no such fault instance is latched on this domain/partition");
  const Row r = row(FaultState::kClearedUnacknowledged, 3);
  EXPECT_EQ(refusal_reason({1, Sensor::kGyro, 2}, &r), "stale sequence (current #3, cleared)");
  EXPECT_EQ(refusal_reason({1, Sensor::kGyro, 4}, &r), "unknown sequence (current #3, cleared)");
  EXPECT_EQ(refusal_reason({1, Sensor::kGyro, 3}, &r),
            "no confirmation from the sidecar (current #3, cleared)");
  const Row n = row(FaultState::kNormal, 3);
  EXPECT_EQ(refusal_reason({1, Sensor::kGyro, 3}, &n),
            "nothing to acknowledge (current #3, normal)");
}

TEST(AckProtocol, AnAckIsWrittenIntoItsVesselsPartitionOnly) {
  EXPECT_EQ(ack_partitions({"vessel-*"}, 257000002), std::vector<std::string>{"vessel-257000002"});
  EXPECT_EQ(ack_partitions({"t_12_vessel-*"}, 7), std::vector<std::string>{"t_12_vessel-7"});
  EXPECT_EQ(ack_partitions({"fleet"}, 7), std::vector<std::string>{"fleet"});
  EXPECT_EQ(ack_partitions({}, 7), std::vector<std::string>{});
}

TEST(MonitorFormat, AFaultRowAsJson) {
  const js::Value v =
      js::Parser(json_row(row(FaultState::kRaised, 1, "J_N \x1b[2J 14 > 12"), 0.5, 1002.0))
          .parse_document();
  EXPECT_EQ(v.at("type").str, "fault");
  EXPECT_EQ(v.at("mmsi").num, 257000001);
  EXPECT_EQ(v.at("sensor").str, "gyro");
  EXPECT_EQ(v.at("state").str, "raised");
  EXPECT_EQ(v.at("sequence").num, 1);
  EXPECT_EQ(v.at("age_s").num, 2.0);
  EXPECT_EQ(v.at("heard_age_s").num, 0.5);
  EXPECT_TRUE(v.at("alive").b);
  EXPECT_EQ(v.at("message").str, "J_N \\x1b[2J 14 > 12");
}

TEST(MonitorFormat, TheTableEscapesMessagesAndMarksGoneSidecarsAndConflicts) {
  InstanceOwners<RowKey, Row> rows;
  Row r = row(FaultState::kRaised, 1, "all clear\r\x1b[31m");
  r.alive = false;
  rows.offer({r.mmsi, 1}, r.mmsi, WriterRef{"w1", 0}, 1, r);
  VesselLiveness live(5.0);
  VesselLiveness::Change c;
  live.heard(257000001, 10.0, &c);
  const std::string t = format_table(rows, nullptr, live, 2, 1003.0, 11.0);
  EXPECT_EQ(t.find('\x1b'), std::string::npos) << t;
  EXPECT_EQ(t.find('\r'), std::string::npos) << t;
  EXPECT_NE(t.find("all clear\\r\\x1b[31m"), std::string::npos) << t;
  EXPECT_NE(t.find("raised?"), std::string::npos) << t;
  EXPECT_NE(t.find("'?': sidecar gone"), std::string::npos) << t;
  EXPECT_NE(t.find("!! 2 conflicting writer(s)"), std::string::npos) << t;
  EXPECT_NE(t.find("vessel 257000001 (sidecar gone): last heard 1.0 s ago"), std::string::npos)
      << t;
}

TEST(MonitorFormat, AConflictAsJson) {
  OwnerDecision d;
  d.verdict = OwnerDecision::Verdict::kRefused;
  d.why = OwnerDecision::Why::kForeignVessel;
  d.owner = WriterRef{"owner-guid", 7};
  d.owner_sequence = 1;
  const js::Value v =
      js::Parser(json_conflict(d, 7, "gyro", "forger-guid", 100, "normal")).parse_document();
  EXPECT_EQ(v.at("type").str, "conflict");
  EXPECT_EQ(v.at("verdict").str, "refused");
  EXPECT_EQ(v.at("why").str, "writer confined to another vessel");
  EXPECT_EQ(v.at("writer").str, "forger-guid");
  EXPECT_EQ(v.at("owner").str, "owner-guid");
  EXPECT_EQ(v.at("sequence").num, 100);
  EXPECT_EQ(v.at("owner_sequence").num, 1);
}

TEST(MonitorFormat, SilenceChanges) {
  EXPECT_EQ(change_line({257000001, true, 5.1, 0.0}, 5.0),
            "vessel 257000001 silent: nothing heard for 5.1 s (> 5 s)");
  EXPECT_EQ(change_line({257000001, false, 0.0, 9.8}, 5.0),
            "vessel 257000001 heard again after 9.8 s of silence");
  const js::Value v = js::Parser(json_change({257000001, false, 0.0, 9.8}, 5.0)).parse_document();
  EXPECT_EQ(v.at("type").str, "vessel");
  EXPECT_FALSE(v.at("silent").b);
  EXPECT_EQ(v.at("gap_s").num, 9.8);
}

// ------------------------------------------------------------------ roster (issue 14, item 4)

TEST(Roster, OneMmsiPerLineWithCommentsAndTheReasonForABadLine) {
  std::set<std::uint32_t> r;
  std::string why;
  ASSERT_TRUE(parse_roster("# the fleet\n257000001\n  257000002  # Otter 2\n\n257000001\r\n",
                           "fleet.txt", &r, &why))
      << why;
  EXPECT_EQ(r, (std::set<std::uint32_t>{257000001, 257000002}));
  EXPECT_FALSE(parse_roster("257000001\n25700000x\n", "fleet.txt", &r, &why));
  EXPECT_NE(why.find("fleet.txt:2: '25700000x' is not an MMSI"), std::string::npos) << why;
  EXPECT_FALSE(parse_roster("1000000000\n", "f", &r, &why));
  EXPECT_FALSE(parse_roster("0\n", "f", &r, &why));
  EXPECT_FALSE(parse_roster("257000001 257000002\n", "f", &r, &why));
  EXPECT_FALSE(parse_roster("# nobody\n\n", "f", &r, &why));
  EXPECT_NE(why.find("no MMSI"), std::string::npos) << why;
}

TEST(Roster, AVesselNeverHeardIsReportedAfterTheGraceAndOnceHeardAgain) {
  // GIVEN a roster of two vessels, a monitor started at t=100 s with a 5 s grace
  VesselLiveness live(5.0);
  RosterWatch w({1, 2}, 100.0, 5.0);
  VesselLiveness::Change c;
  live.heard(1, 101.0, &c);
  // WHEN nothing is heard from vessel 2 within the grace THEN nothing is reported yet
  EXPECT_TRUE(w.evaluate(live, 104.0).empty());
  EXPECT_EQ(w.state(2, live), RosterState::kNeverHeard);
  EXPECT_EQ(w.never_heard(live), std::vector<std::uint32_t>{2});
  // WHEN the grace has passed THEN vessel 2 is reported never heard, once
  auto ch = w.evaluate(live, 105.5);
  ASSERT_EQ(ch.size(), 1u);
  EXPECT_EQ(ch[0].mmsi, 2u);
  EXPECT_EQ(ch[0].state, RosterState::kNeverHeard);
  EXPECT_EQ(roster_line(ch[0]), "vessel 2 (on roster): never heard (5.5 s since start)");
  EXPECT_TRUE(w.evaluate(live, 106.0).empty());
  // WHEN vessel 2 and vessel 3 (not on the roster) are heard THEN both are reported, once
  live.heard(2, 107.0, &c);
  live.heard(3, 107.0, &c);
  ch = w.evaluate(live, 107.0);
  ASSERT_EQ(ch.size(), 2u);
  EXPECT_EQ(ch[0].state, RosterState::kHeard);
  EXPECT_EQ(ch[1].mmsi, 3u);
  EXPECT_EQ(ch[1].state, RosterState::kNotOnRoster);
  EXPECT_EQ(roster_line(ch[1]), "vessel 3 heard: not on roster");
  EXPECT_TRUE(w.evaluate(live, 108.0).empty());
  EXPECT_EQ(w.shown(live), (std::vector<std::uint32_t>{1, 2, 3}));
  // AND a roster vessel gone silent is silent against the roster
  live.evaluate(200.0);
  EXPECT_EQ(w.state(1, live), RosterState::kSilent);
  // AND without a roster nothing is ever reported
  RosterWatch none;
  EXPECT_TRUE(none.evaluate(live, 1000.0).empty());
  EXPECT_EQ(none.state(3, live), RosterState::kNoRoster);
}

TEST(Roster, TheTableAndJsonShowTheVesselsNeverHeardAndThoseNotOnTheRoster) {
  InstanceOwners<RowKey, Row> rows;
  const Row r = row(FaultState::kRaised, 1);
  rows.offer({r.mmsi, 1}, r.mmsi, WriterRef{"w1", 0}, 1, r);
  VesselLiveness live(5.0);
  VesselLiveness::Change c;
  live.heard(257000001, 10.0, &c);
  live.heard(257000009, 10.0, &c);
  const RosterWatch w({257000001, 257000002}, 0.0, 5.0);
  TableExtras extras;
  extras.roster = &w;
  const std::string t = format_table(rows, nullptr, live, 0, 1003.0, 11.0, extras);
  EXPECT_NE(t.find("!! 1 of 2 roster vessel(s) never heard"), std::string::npos) << t;
  EXPECT_NE(t.find("vessel 257000002 (on roster): never heard"), std::string::npos) << t;
  EXPECT_NE(t.find("vessel 257000001: last heard 1.0 s ago\n"), std::string::npos) << t;
  EXPECT_NE(t.find("vessel 257000009: last heard 1.0 s ago (not on roster)"), std::string::npos)
      << t;
  // Without a roster the table is as before
  const std::string plain = format_table(rows, nullptr, live, 0, 1003.0, 11.0);
  EXPECT_EQ(plain.find("roster"), std::string::npos) << plain;

  js::Value v = js::Parser(json_roster(257000002, RosterState::kNeverHeard, NAN)).parse_document();
  EXPECT_EQ(v.at("type").str, "roster");
  EXPECT_EQ(v.at("mmsi").num, 257000002);
  EXPECT_EQ(v.at("state").str, "never_heard");
  EXPECT_TRUE(v.at("on_roster").b);
  EXPECT_FALSE(v.at("heard").b);
  v = js::Parser(json_roster(257000009, RosterState::kNotOnRoster, 1.0)).parse_document();
  EXPECT_EQ(v.at("state").str, "not_on_roster");
  EXPECT_FALSE(v.at("on_roster").b);
  EXPECT_TRUE(v.at("heard").b);
}

TEST(DiscoveryLimit, WarnsWhenTheParticipantsApproachAndReachTheLimit) {
  EXPECT_EQ(discovery_limit_level(100, 0), 0);  // no limit (multicast, discovery server)
  EXPECT_EQ(discovery_limit_level(5, 32), 0);
  EXPECT_EQ(discovery_limit_level(23, 32), 0);
  EXPECT_EQ(discovery_limit_level(24, 32), 1);
  EXPECT_EQ(discovery_limit_level(31, 32), 1);
  EXPECT_EQ(discovery_limit_level(32, 32), 2);
  EXPECT_EQ(discovery_limit_level(100, 32), 2);
}

// ------------------------------------------------------------------ --once (issue 12, section 3)

TEST(LatchedStateWait, CompleteOnceDiscoverySettledStatusesArrivedAndEventWritersSettled) {
  using T = LatchedStateWait::Topic;
  const double q = LatchedStateWait::kDiscoveryQuiet;
  const double e = LatchedStateWait::kEventSettle;
  LatchedStateWait w;
  // GIVEN nothing matched THEN not complete (no sidecar)
  EXPECT_FALSE(w.complete(100.0, false, {}));
  EXPECT_EQ(w.pending(100.0, false, {}), std::vector<std::string>{"no sidecar's writer matched"});
  // WHEN a sidecar's two writers match at t=1
  w.matched(T::kFaultEvent, "ev1", 1.0);
  w.matched(T::kStatus, "st1", 1.0);
  // THEN it waits for its status and for the event writer to settle
  EXPECT_FALSE(w.complete(1.0 + std::max(q, e) + 0.1, false, {}));
  w.status_sample("st1");
  EXPECT_FALSE(w.complete(1.0 + std::min(q, e) * 0.5, false, {}));
  EXPECT_TRUE(w.complete(1.0 + std::max(q, e) + 0.01, false, {}));
  // WHEN another sidecar matches THEN discovery is not settled until it has been quiet
  w.matched(T::kFaultEvent, "ev2", 5.0);
  EXPECT_FALSE(w.complete(5.0 + q * 0.5, false, {}));
  EXPECT_TRUE(w.complete(5.0 + std::max(q, e) + 0.01, false, {}));
  // WHEN a status writer matched and left without a sample THEN nothing is awaited from it
  w.matched(T::kStatus, "st3", 10.0);
  EXPECT_FALSE(w.complete(12.0, false, {}));
  const auto p = w.pending(12.0, false, {});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NE(p[0].find("FdiStatus writer st3"), std::string::npos) << p[0];
  w.unmatched(T::kStatus, "st3");
  EXPECT_TRUE(w.complete(12.0, false, {}));
  // AND with a roster, a vessel not heard keeps it incomplete (even with writers settled)
  EXPECT_FALSE(w.complete(12.0, true, {257000002}));
  EXPECT_EQ(w.pending(12.0, true, {257000002}),
            std::vector<std::string>{"roster vessel 257000002 not heard"});
  // AND with a roster all heard, no match is needed
  LatchedStateWait empty;
  EXPECT_TRUE(empty.complete(0.0, true, {}));
}

// ------------------------------------------------------------------ the table's output (item 5)

/// A fleet of `vessels` vessels, two fault instances each, every instance updated `rounds` times
/// one after the other (one change per turn of the monitor's loop); returns the lines printed by
/// a non-terminal TableOutput, and in `*reprinted` those of a full table on every change (the
/// monitor before issue 14's item 5).
std::size_t lines_for_fleet(int vessels, int rounds, std::size_t* reprinted, std::size_t* changes) {
  InstanceOwners<RowKey, Row> rows;
  VesselLiveness live(5.0);
  std::string out;
  TableOutput table(false, [&out](const std::string& s) { out += s; });
  *reprinted = 0;
  *changes = 0;
  double mono = 0.0;
  for (int k = 1; k <= rounds; ++k) {
    for (int v = 0; v < vessels; ++v) {
      for (const Sensor s : {Sensor::kGyro, Sensor::kAccelerometer}) {
        Row r = row(k % 2 == 1 ? FaultState::kRaised : FaultState::kClearedUnacknowledged,
                    static_cast<std::uint64_t>(k));
        r.mmsi = 257000000u + static_cast<std::uint32_t>(v);
        r.ev.sensor = s;
        rows.offer({r.mmsi, static_cast<int>(s)}, r.mmsi, WriterRef{"w" + std::to_string(v), 0},
                   r.ev.sequence, r);
        VesselLiveness::Change c;
        live.heard(r.mmsi, mono, &c);
        const TableInput in{rows, nullptr, live, 0, nullptr};
        table.update(in, true, 1000.0 + mono, mono);
        const std::string full = format_table(rows, nullptr, live, 0, 1000.0 + mono, mono);
        *reprinted += static_cast<std::size_t>(std::count(full.begin(), full.end(), '\n'));
        ++*changes;
        mono += 0.01;
      }
    }
  }
  const TableInput in{rows, nullptr, live, 0, nullptr};
  table.finish(in, 1000.0 + mono, mono);
  EXPECT_EQ(table.lines(), static_cast<std::size_t>(std::count(out.begin(), out.end(), '\n')));
  EXPECT_EQ(out.find('\x1b'), std::string::npos) << "no terminal control in a pipe";
  return table.lines();
}

TEST(TableOutput, OffATerminalTheLinesPrintedGrowLinearlyWithTheChanges) {
  // GIVEN fleets of 5 and of 40 vessels, each fault instance raised and cleared 4 times
  std::size_t old5 = 0, old40 = 0, n5 = 0, n40 = 0;
  const std::size_t lines5 = lines_for_fleet(5, 4, &old5, &n5);
  const std::size_t lines40 = lines_for_fleet(40, 4, &old40, &n40);
  std::printf("lines printed for %zu changes (5 vessels): %zu (a full table per change: %zu)\n", n5,
              lines5, old5);
  std::printf("lines printed for %zu changes (40 vessels): %zu (a full table per change: %zu)\n",
              n40, lines40, old40);
  // THEN each change after the first table is one line, and the start and the end one table
  // each: header, one row per instance, the count line, one line per vessel
  const auto table_lines = [](std::size_t vessels) { return 2 + 2 * vessels + vessels; };
  EXPECT_EQ(lines5, 4 + (n5 - 1) + table_lines(5));
  EXPECT_EQ(lines40, 4 + (n40 - 1) + table_lines(40));
  // AND so 8 times the fleet and the changes print about 8 times the lines, not 64 times
  EXPECT_LT(static_cast<double>(lines40) / static_cast<double>(lines5), 9.0);
  EXPECT_GT(static_cast<double>(old40) / static_cast<double>(old5), 30.0);
}

TEST(TableOutput, OnATerminalRedrawsInPlaceAtABoundedRateAndMarksChangedRows) {
  InstanceOwners<RowKey, Row> rows;
  VesselLiveness live(5.0);
  std::vector<std::string> draws;
  TableOutput table(true, [&draws](const std::string& s) { draws.push_back(s); });
  // GIVEN a first row, drawn after one redraw interval (the latched state comes as a burst)
  Row r = row(FaultState::kRaised, 1);
  rows.offer({r.mmsi, 1}, r.mmsi, WriterRef{"w1", 0}, 1, r);
  const TableInput in{rows, nullptr, live, 0, nullptr};
  table.update(in, true, 1000.0, -0.2);
  EXPECT_TRUE(draws.empty());
  table.update(in, false, 1000.0, 0.0);
  ASSERT_EQ(draws.size(), 1u);
  EXPECT_EQ(draws[0].rfind("\x1b[H\x1b[2J", 0), 0u) << "cursor home and clear";
  EXPECT_EQ(draws[0].find("* 257000001"), std::string::npos) << "nothing changed yet";
  // WHEN the row changes 100 times within one second
  for (int i = 0; i < 100; ++i) {
    r.ev.sequence = static_cast<std::uint64_t>(i + 2);
    rows.offer({r.mmsi, 1}, r.mmsi, WriterRef{"w1", 0}, r.ev.sequence, r);
    table.update(in, true, 1000.0, 0.01 * (i + 1));
  }
  // THEN it was redrawn at most kMaxRedrawRate times in that second, the changes coalesced
  EXPECT_LE(draws.size(), 1u + static_cast<std::size_t>(TableOutput::kMaxRedrawRate));
  EXPECT_GE(draws.size(), 2u);
  // AND the last state is drawn within one redraw interval, its row marked
  table.update(in, false, 1000.0, 1.0 + 1.0 / TableOutput::kMaxRedrawRate);
  EXPECT_NE(draws.back().find("* 257000001"), std::string::npos) << draws.back();
  EXPECT_NE(draws.back().find(" 101 "), std::string::npos) << draws.back();
  // AND without a change it is redrawn once a second (the ages), the mark gone after a while
  const std::size_t before = draws.size();
  table.update(in, false, 1000.0, 1.5);
  EXPECT_EQ(draws.size(), before);
  table.update(in, false, 1000.0, 1.0 + TableOutput::kMarkSeconds + 1.0);
  ASSERT_EQ(draws.size(), before + 1);
  EXPECT_EQ(draws.back().find("* 257000001"), std::string::npos) << draws.back();
  EXPECT_NE(draws.back().find("  257000001"), std::string::npos) << draws.back();
}

}  // namespace
}  // namespace usvfdi::app
