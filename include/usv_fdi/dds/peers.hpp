// What a participant knows about its remote peers, from Fast DDS discovery: the subject name of
// each remote participant's authenticated identity (DDS Security; "" without it) and the topic and
// partitions of each remote writer. A DdsContext installs one as its participant listener, so the
// directory is filled before any sample of a remote writer can arrive (discovery of the writer
// precedes its match). Thread-safe: Fast DDS calls it from its discovery threads, the application
// reads it from its own.
#pragma once

#include <fastdds/rtps/common/InstanceHandle.h>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>

#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace usvfdi::dds {

class PeerDirectory : public eprosima::fastdds::dds::DomainParticipantListener {
 public:
  struct Writer {
    std::string topic;
    std::vector<std::string> partitions;  ///< as the writer declared them (empty: default)
    std::string subject;  ///< its participant's authenticated identity ("" : none / unknown)
  };

  /// The remote writer behind a sample's SampleInfo::publication_handle (nullopt: not discovered).
  std::optional<Writer> writer(const eprosima::fastrtps::rtps::InstanceHandle_t& publication) const;
  /// The remote participants discovered and not removed (or dropped) since.
  std::size_t participant_count() const;
  /// The subject name of the identity of the participant that owns `publication` ("" : unknown).
  std::string subject_of(const eprosima::fastrtps::rtps::InstanceHandle_t& publication) const;

  void on_participant_discovery(eprosima::fastdds::dds::DomainParticipant*,
                                eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override;
  void on_publisher_discovery(eprosima::fastdds::dds::DomainParticipant*,
                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override;

 private:
  mutable std::mutex m_;
  std::map<eprosima::fastrtps::rtps::GuidPrefix_t, std::string> subjects_;
  std::set<eprosima::fastrtps::rtps::GuidPrefix_t> participants_;
  std::map<eprosima::fastrtps::rtps::GUID_t, Writer> writers_;
};

/// The CN of a subject name, in OpenSSL's one-line form as PKI-DH announces it
/// ("/C=NO/O=usv-fdi test fleet/OU=shore/CN=shore" -> "shore") or in RFC 2253
/// ("CN=shore,OU=shore,O=usv-fdi test fleet,C=NO"); "" if it has none.
std::string common_name(const std::string& subject);

/// The operator id of an acknowledgement written by a participant with identity `subject`: the
/// identity's CN, followed by ":" and the id the writer claims when that differs (the claim names a
/// person within the authenticated identity, it authenticates nothing). `subject` "": the identity
/// could not be determined: "?" (with the claim).
std::string operator_of(const std::string& subject, const std::string& claimed);

/// The MMSI of a vessel partition: PREFIX + "vessel-" + digits (1..999999999) -> the MMSI, else 0.
/// (Wildcards are not a vessel: "vessel-*" -> 0.)
std::uint32_t vessel_of_partition(const std::string& partition);

/// The vessel a writer is confined to: the MMSI of its only partition, 0 if it has none or several.
std::uint32_t vessel_of_writer(const std::vector<std::string>& partitions);

}  // namespace usvfdi::dds
