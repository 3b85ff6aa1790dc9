// RAII owner of one Fast DDS domain participant with the usv-fdi topics, one publisher and one
// subscriber. Every entity is created from named XML profiles; every failure throws
// std::runtime_error naming what failed. Independent of usv_fdi::core (conversions live elsewhere).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <fastdds/dds/core/status/StatusMask.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#include "usv_fdi/dds/peers.hpp"
#include "usv_fdi/dds/profiles.hpp"
#include "usv_fdi/dds/types.hpp"

namespace usvfdi::dds {

/// DDS topic names, indexed by TopicId.
struct TopicNames {
  std::string ins = "usv_fdi/ins";
  std::string rudder = "usv_fdi/rudder";
  std::string fault_event = "usv_fdi/fault_event";
  std::string fault_ack = "usv_fdi/fault_ack";
  std::string status = "usv_fdi/status";
  std::string speed = "usv_fdi/speed";  ///< optional surge speed (data model version 3)

  const std::string& operator[](TopicId id) const;
};

struct DdsConfig {
  /// XML profiles file loaded before the participant is created (see load_profiles_file()).
  /// Empty: rely on FASTRTPS_DEFAULT_PROFILES_FILE / DEFAULT_FASTRTPS_PROFILES.xml only.
  std::string profiles_file;
  /// DDS domain id. Fast DDS's default UDP port mapping limits it to 0..232.
  std::uint32_t domain_id = 0;
  /// Participant profile name in the loaded XML.
  std::string participant_profile = profiles::kParticipant;
  TopicNames topics;
  /// Partitions of the publisher / subscriber (empty: the default partition).
  std::vector<std::string> publisher_partitions;
  std::vector<std::string> subscriber_partitions;
};

class DdsContext {
 public:
  /// Loads the profiles, creates the participant, registers the five types, creates the five
  /// topics, the publisher and the subscriber. Throws std::runtime_error; on throw everything that
  /// was created is deleted again.
  explicit DdsContext(DdsConfig config);
  /// delete_contained_entities() then delete_participant(). Listeners passed to create_writer /
  /// create_reader must outlive the context (or the entity, if deleted earlier).
  ~DdsContext();

  DdsContext(const DdsContext&) = delete;
  DdsContext& operator=(const DdsContext&) = delete;
  DdsContext(DdsContext&&) = delete;
  DdsContext& operator=(DdsContext&&) = delete;

  const DdsConfig& config() const noexcept { return config_; }
  eprosima::fastdds::dds::DomainParticipant& participant() const noexcept { return *participant_; }
  eprosima::fastdds::dds::Publisher& publisher() const noexcept { return *publisher_; }
  eprosima::fastdds::dds::Subscriber& subscriber() const noexcept { return *subscriber_; }
  eprosima::fastdds::dds::Topic& topic(TopicId id) const;
  /// The remote participants' identities and writers' partitions (the participant's listener).
  const PeerDirectory& peers() const noexcept { return *peers_; }
  /// True if the participant runs DDS Security (its profile sets an authentication plugin).
  bool secure() const;

  /// Creates a data writer on topic `id` from data writer profile `profile`. The writer is owned
  /// by the context (deleted with it, or earlier by delete_writer()).
  eprosima::fastdds::dds::DataWriter& create_writer(
      TopicId id, const std::string& profile,
      eprosima::fastdds::dds::DataWriterListener* listener = nullptr,
      const eprosima::fastdds::dds::StatusMask& mask = eprosima::fastdds::dds::StatusMask::all());
  /// Like create_writer(), on a publisher of its own in `partitions` instead of the configured
  /// ones (e.g. an acknowledgement written into one vessel's partition only).
  eprosima::fastdds::dds::DataWriter& create_writer_in_partitions(
      TopicId id, const std::string& profile, const std::vector<std::string>& partitions);
  /// Creates a data reader on topic `id` from data reader profile `profile`; see create_writer().
  eprosima::fastdds::dds::DataReader& create_reader(
      TopicId id, const std::string& profile,
      eprosima::fastdds::dds::DataReaderListener* listener = nullptr,
      const eprosima::fastdds::dds::StatusMask& mask = eprosima::fastdds::dds::StatusMask::all());

  /// Like create_reader(), for the samples of one vessel only: a content-filtered topic
  /// "mmsi = <mmsi>" on topic `id` (whose type has an `mmsi` member). Writers that filter on
  /// their side (Fast DDS does, up to their writer_resource_limits.reader_filters_allocation
  /// readers) then do not send other vessels' samples to this reader at all; the others are
  /// filtered on arrival, before the listener.
  eprosima::fastdds::dds::DataReader& create_vessel_reader(
      TopicId id, const std::string& profile, std::uint32_t mmsi,
      eprosima::fastdds::dds::DataReaderListener* listener = nullptr,
      const eprosima::fastdds::dds::StatusMask& mask = eprosima::fastdds::dds::StatusMask::all());

  /// Typed shorthands: the topic follows from the data type.
  template <class T>
  eprosima::fastdds::dds::DataWriter& create_writer(const std::string& profile) {
    return create_writer(TopicTraits<T>::kTopic, profile);
  }
  template <class T>
  eprosima::fastdds::dds::DataReader& create_reader(const std::string& profile) {
    return create_reader(TopicTraits<T>::kTopic, profile);
  }

  /// Deletes a writer / reader created by this context. Throws std::runtime_error on failure.
  void delete_writer(eprosima::fastdds::dds::DataWriter& writer);
  void delete_reader(eprosima::fastdds::dds::DataReader& reader);

 private:
  struct ParticipantDeleter {
    void operator()(eprosima::fastdds::dds::DomainParticipant* participant) const noexcept;
  };

  DdsConfig config_;
  std::unique_ptr<PeerDirectory> peers_;  ///< outlives the participant (its listener)
  std::unique_ptr<eprosima::fastdds::dds::DomainParticipant, ParticipantDeleter> participant_;
  std::array<eprosima::fastdds::dds::Topic*, kTopicCount> topics_{};
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
};

namespace detail {
[[noreturn]] void throw_write_failed(const eprosima::fastdds::dds::DataWriter& writer);
}  // namespace detail

/// Writes one sample. `writer` must belong to T's topic (not checked: Fast DDS takes a void*).
/// Throws std::runtime_error if Fast DDS refuses it (e.g. a reliable writer
/// blocked longer than max_blocking_time, or resource limits reached).
template <class T>
void write(eprosima::fastdds::dds::DataWriter& writer, const T& sample) {
  static_assert(sizeof(TopicTraits<T>) > 0, "not a usv-fdi DDS type");
  if (!writer.write(const_cast<T*>(&sample))) {
    detail::throw_write_failed(writer);
  }
}

/// Takes every available sample with valid data from `reader` and appends it (and its SampleInfo,
/// if `infos` is given) to `out`. Returns the number of samples appended.
template <class T>
std::size_t take_all(eprosima::fastdds::dds::DataReader& reader, std::vector<T>& out,
                     std::vector<eprosima::fastdds::dds::SampleInfo>* infos = nullptr) {
  static_assert(sizeof(TopicTraits<T>) > 0, "not a usv-fdi DDS type");
  std::size_t n = 0;
  T sample;
  eprosima::fastdds::dds::SampleInfo info;
  while (reader.take_next_sample(&sample, &info) ==
         eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
    if (!info.valid_data) continue;
    out.push_back(sample);
    if (infos != nullptr) infos->push_back(info);
    ++n;
  }
  return n;
}

}  // namespace usvfdi::dds
