// InstanceOwners: only the writer that owns an instance updates what the monitor shows (issue 15,
// High 1), and the DDS helpers that tell which vessel a writer is confined to.
#include <gtest/gtest.h>

#include <string>

#include "instance_owners.hpp"
#include "usv_fdi/dds/peers.hpp"

namespace usvfdi::app {
namespace {

using Owners = InstanceOwners<int, std::string>;
using V = OwnerDecision::Verdict;
using W = OwnerDecision::Why;

WriterRef writer(const std::string& id, std::uint32_t vessel = 0) { return WriterRef{id, vessel}; }

TEST(InstanceOwners, TheFirstWriterOwnsAndASecondWriterIsHeldAndReportedOnce) {
  Owners o;
  EXPECT_EQ(o.offer(1, 7, writer("sidecar"), 1, "raised").verdict, V::kShown);
  const OwnerDecision d = o.offer(1, 7, writer("forger"), 100, "normal");
  EXPECT_EQ(d.verdict, V::kHeld);
  EXPECT_EQ(d.why, W::kSecondWriter);
  EXPECT_TRUE(d.report);
  EXPECT_EQ(d.owner.id, "sidecar");
  EXPECT_EQ(d.owner_sequence, 1u);
  EXPECT_EQ(*o.shown(1), "raised");
  // reported once per writer
  EXPECT_FALSE(o.offer(1, 7, writer("forger"), 101, "normal").report);
  EXPECT_EQ(*o.shown(1), "raised");
  // the owner goes on
  EXPECT_EQ(o.offer(1, 7, writer("sidecar"), 2, "cleared").verdict, V::kShown);
  EXPECT_EQ(*o.shown(1), "cleared");
}

TEST(InstanceOwners, TheOwnersSequenceNeverGoesBackwards) {
  Owners o;
  o.offer(1, 7, writer("w"), 5, "raised");
  const OwnerDecision d = o.offer(1, 7, writer("w"), 4, "normal");
  EXPECT_EQ(d.verdict, V::kRefused);
  EXPECT_EQ(d.why, W::kBackwards);
  EXPECT_EQ(*o.shown(1), "raised");
  EXPECT_EQ(o.offer(1, 7, writer("w"), 5, "raised again").verdict, V::kShown);  // a re-delivery
}

TEST(InstanceOwners, AWriterConfinedToAnotherVesselIsRefusedEvenFirst) {
  Owners o;
  const OwnerDecision d = o.offer(1, 7, writer("other", 8), 100, "normal");
  EXPECT_EQ(d.verdict, V::kRefused);
  EXPECT_EQ(d.why, W::kForeignVessel);
  EXPECT_TRUE(d.report);
  EXPECT_EQ(o.shown(1), nullptr);
  EXPECT_EQ(o.size(), 0u);
  EXPECT_FALSE(o.offer(1, 7, writer("other", 8), 101, "normal").report);
  EXPECT_EQ(o.offer(1, 7, writer("sidecar", 7), 1, "raised").verdict, V::kShown);
  EXPECT_EQ(*o.shown(1), "raised");
}

TEST(InstanceOwners, AnAuthenticatedWriterDisplacesAnUnauthenticatedOwner) {
  Owners o;
  o.offer(1, 7, writer("forger"), 100, "normal");  // first, but not authenticated
  const OwnerDecision d = o.offer(1, 7, writer("sidecar", 7), 1, "raised");
  EXPECT_EQ(d.verdict, V::kShown);
  EXPECT_EQ(d.why, W::kTakeover);
  EXPECT_TRUE(d.report);
  EXPECT_EQ(*o.shown(1), "raised");
  EXPECT_EQ(o.offer(1, 7, writer("forger"), 101, "normal").verdict, V::kHeld);
  EXPECT_EQ(*o.shown(1), "raised");
}

TEST(InstanceOwners, WhenTheOwnerLeavesTheHeldWriterWithTheHighestSequenceTakesOver) {
  Owners o;
  o.offer(1, 7, writer("old"), 3, "raised");
  o.offer(1, 7, writer("a"), 3, "raised (restarted)");
  o.offer(1, 7, writer("b"), 2, "stale");
  const auto changed = o.writer_gone("old");
  ASSERT_EQ(changed.size(), 1u);
  ASSERT_TRUE(changed[0].second.has_value());
  EXPECT_EQ(changed[0].second->id, "a");
  EXPECT_EQ(*o.shown(1), "raised (restarted)");
  EXPECT_EQ(o.owner(1)->id, "a");
}

TEST(InstanceOwners, AForgerThatLeavesLeavesNothingBehind) {
  Owners o;
  o.offer(1, 7, writer("sidecar"), 1, "raised");
  o.offer(1, 7, writer("forger"), 100, "normal");
  EXPECT_TRUE(o.writer_gone("forger").empty());
  // the sidecar leaves later: nothing held any more, the row stays the sidecar's, marked gone
  const auto changed = o.writer_gone("sidecar");
  ASSERT_EQ(changed.size(), 1u);
  EXPECT_FALSE(changed[0].second.has_value());
  EXPECT_EQ(*o.shown(1), "raised");
  // a new writer after the owner left takes over (a restarted sidecar), even at a lower sequence
  const OwnerDecision d = o.offer(1, 7, writer("restarted"), 1, "raised");
  EXPECT_EQ(d.verdict, V::kShown);
  EXPECT_EQ(d.why, W::kOwnerGone);
}

TEST(InstanceOwners, AnOwnerThatComesBackKeepsItsInstances) {
  Owners o;
  o.offer(1, 7, writer("sidecar"), 1, "raised");
  o.writer_gone("sidecar");
  o.writer_back("sidecar");
  EXPECT_EQ(o.offer(1, 7, writer("other"), 2, "normal").verdict, V::kHeld);
}

TEST(PeerHelpers, CommonNameOfBothSubjectForms) {
  EXPECT_EQ(usvfdi::dds::common_name("/C=NO/O=usv-fdi test fleet/OU=shore/CN=shore2"), "shore2");
  EXPECT_EQ(usvfdi::dds::common_name("CN=shore,OU=shore,O=usv-fdi test fleet,C=NO"), "shore");
  EXPECT_EQ(usvfdi::dds::common_name("CN=a\\,b,O=x"), "a,b");
  EXPECT_EQ(usvfdi::dds::common_name("/C=NO/O=x"), "");
  EXPECT_EQ(usvfdi::dds::common_name(""), "");
}

TEST(PeerHelpers, TheVesselOfAPartitionAndOfAWriter) {
  using usvfdi::dds::vessel_of_partition;
  using usvfdi::dds::vessel_of_writer;
  EXPECT_EQ(vessel_of_partition("vessel-257000001"), 257000001u);
  EXPECT_EQ(vessel_of_partition("test_12_vessel-257000002"), 257000002u);
  EXPECT_EQ(vessel_of_partition("vessel-*"), 0u);
  EXPECT_EQ(vessel_of_partition("vessel-2570000011"), 0u);  // 10 digits
  EXPECT_EQ(vessel_of_partition("vessel-0123"), 0u);
  EXPECT_EQ(vessel_of_partition("fleet"), 0u);
  EXPECT_EQ(vessel_of_writer({"vessel-7"}), 7u);
  EXPECT_EQ(vessel_of_writer({"vessel-7", "vessel-8"}), 0u);
  EXPECT_EQ(vessel_of_writer({}), 0u);
}

TEST(PeerHelpers, TheOperatorOfAnAckIsTheAuthenticatedIdentity) {
  using usvfdi::dds::operator_of;
  EXPECT_EQ(operator_of("/C=NO/OU=shore/CN=shore", "alice"), "shore:alice");
  EXPECT_EQ(operator_of("/C=NO/OU=shore/CN=shore", "shore"), "shore");
  EXPECT_EQ(operator_of("/C=NO/OU=shore/CN=shore", ""), "shore");
  EXPECT_EQ(operator_of("", "captain"), "?:captain");
}

}  // namespace
}  // namespace usvfdi::app
