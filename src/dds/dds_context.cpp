#include "usv_fdi/dds/dds_context.hpp"

#include <stdexcept>
#include <string>
#include <utility>

#include <fastrtps/attributes/LibrarySettingsAttributes.h>
#include <fastrtps/types/TypesBase.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/qos/PublisherQos.hpp>
#include <fastdds/dds/subscriber/qos/SubscriberQos.hpp>
#include <fastdds/dds/topic/ContentFilteredTopic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include <fastdds/dds/topic/qos/TopicQos.hpp>
#include "usv_fdiTypeObject.h"

namespace usvfdi::dds {
namespace {

namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::types::ReturnCode_t;

[[noreturn]] void fail(const std::string& what) {
  throw std::runtime_error("usvfdi::dds: " + what);
}

template <class PubSubType>
void register_type(fdds::DomainParticipant& participant) {
  fdds::TypeSupport type(new PubSubType());
  // The types are generated with -typeobject only so that the builtin SQL content filter
  // (create_vessel_reader) can read their members; their TypeObject and TypeInformation are not
  // announced in discovery, so what other participants (and other vendors) see is unchanged.
  type->auto_fill_type_object(false);
  type->auto_fill_type_information(false);
  const std::string name = type.get_type_name();
  if (type.register_type(&participant) != ReturnCode_t::RETCODE_OK) {
    fail("registering type '" + name + "' failed");
  }
}

std::string type_name_of(TopicId id) {
  switch (id) {
    case TopicId::kIns:
      return fdi::InsSamplePubSubType().getName();
    case TopicId::kRudder:
      return fdi::RudderSamplePubSubType().getName();
    case TopicId::kFaultEvent:
      return fdi::FaultEventPubSubType().getName();
    case TopicId::kFaultAck:
      return fdi::FaultAckPubSubType().getName();
    case TopicId::kStatus:
      return fdi::FdiStatusPubSubType().getName();
    case TopicId::kSpeed:
      return fdi::SpeedSamplePubSubType().getName();
  }
  fail("invalid topic id");
}

std::size_t index_of(TopicId id) {
  const auto i = static_cast<std::size_t>(id);
  if (i >= kTopicCount) fail("invalid topic id " + std::to_string(i));
  return i;
}

}  // namespace

std::string_view to_string(TopicId id) noexcept {
  switch (id) {
    case TopicId::kIns:
      return "ins";
    case TopicId::kRudder:
      return "rudder";
    case TopicId::kFaultEvent:
      return "fault_event";
    case TopicId::kFaultAck:
      return "fault_ack";
    case TopicId::kStatus:
      return "status";
    case TopicId::kSpeed:
      return "speed";
  }
  return "invalid";
}

const std::string& TopicNames::operator[](TopicId id) const {
  switch (id) {
    case TopicId::kIns:
      return ins;
    case TopicId::kRudder:
      return rudder;
    case TopicId::kFaultEvent:
      return fault_event;
    case TopicId::kFaultAck:
      return fault_ack;
    case TopicId::kStatus:
      return status;
    case TopicId::kSpeed:
      return speed;
  }
  fail("invalid topic id");
}

namespace detail {
void throw_write_failed(const fdds::DataWriter& writer) {
  const fdds::Topic* topic = writer.get_topic();
  fail("write on topic '" + (topic != nullptr ? topic->get_name() : std::string("?")) + "' failed");
}
}  // namespace detail

void DdsContext::ParticipantDeleter::operator()(
    fdds::DomainParticipant* participant) const noexcept {
  if (participant == nullptr) return;
  // Errors cannot be reported from a destructor; Fast DDS logs them.
  (void)participant->delete_contained_entities();
  (void)fdds::DomainParticipantFactory::get_instance()->delete_participant(participant);
}

DdsContext::DdsContext(DdsConfig config) : config_(std::move(config)) {
  if (config_.profiles_file.empty()) {
    load_default_profiles();
  } else {
    load_profiles_file(config_.profiles_file);
  }

  // Participants of one process (the sidecar has two: acks arrive on their own) would hand
  // each other discovery data by pointer, and Fast DDS 2.9 may then touch a reader of a
  // participant already deleted: the sidecar crashed in StatefulWriter::intraprocess_gap
  // while deleting its readers at SIGTERM, a few times in a hundred on a loaded machine.
  // Discovery between them goes over the transports, like between two processes; user data
  // still goes by pointer (with intraprocess delivery off altogether, participants of one
  // process no longer receive each other's samples).
  eprosima::fastrtps::LibrarySettingsAttributes library;
  library.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_USER_DATA_ONLY;
  eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(library);

  auto* factory = fdds::DomainParticipantFactory::get_instance();
  peers_ = std::make_unique<PeerDirectory>();
  // Discovery callbacks only (StatusMask::none(): no entity status reaches this listener).
  participant_.reset(factory->create_participant_with_profile(
      static_cast<fdds::DomainId_t>(config_.domain_id), config_.participant_profile, peers_.get(),
      fdds::StatusMask::none()));
  if (!participant_) {
    fail("creating participant on domain " + std::to_string(config_.domain_id) + " from profile '" +
         config_.participant_profile + "' failed");
  }

  registerusv_fdiTypes();  // the TypeObjects the SQL content filter reads (idempotent)
  register_type<fdi::InsSamplePubSubType>(*participant_);
  register_type<fdi::RudderSamplePubSubType>(*participant_);
  register_type<fdi::FaultEventPubSubType>(*participant_);
  register_type<fdi::FaultAckPubSubType>(*participant_);
  register_type<fdi::FdiStatusPubSubType>(*participant_);
  register_type<fdi::SpeedSamplePubSubType>(*participant_);

  for (std::size_t i = 0; i < kTopicCount; ++i) {
    const auto id = static_cast<TopicId>(i);
    const std::string& name = config_.topics[id];
    topics_[i] = participant_->create_topic(name, type_name_of(id), fdds::TOPIC_QOS_DEFAULT);
    if (topics_[i] == nullptr) {
      fail("creating topic '" + name + "' (" + std::string(to_string(id)) + ") failed");
    }
  }

  fdds::PublisherQos pub_qos = participant_->get_default_publisher_qos();
  for (const auto& p : config_.publisher_partitions) pub_qos.partition().push_back(p.c_str());
  publisher_ = participant_->create_publisher(pub_qos);
  if (publisher_ == nullptr) fail("creating publisher failed");

  fdds::SubscriberQos sub_qos = participant_->get_default_subscriber_qos();
  for (const auto& p : config_.subscriber_partitions) sub_qos.partition().push_back(p.c_str());
  subscriber_ = participant_->create_subscriber(sub_qos);
  if (subscriber_ == nullptr) fail("creating subscriber failed");
}

DdsContext::~DdsContext() = default;

fdds::Topic& DdsContext::topic(TopicId id) const { return *topics_[index_of(id)]; }

bool DdsContext::secure() const {
  for (const auto& p : participant_->get_qos().properties().properties()) {
    if (p.name() == "dds.sec.auth.plugin" && !p.value().empty()) return true;
  }
  return false;
}

/// Readers with a content filter (a sidecar's: "mmsi = M") that one writer filters for on
/// its side; Fast DDS's default is 32, and the readers beyond are sent every sample and filter
/// on arrival. A fleet of sidecars on one partition needs one per sidecar.
constexpr std::uint32_t kMaxReaderFilters = 4096;

fdds::DataWriter& DdsContext::create_writer(TopicId id, const std::string& profile,
                                            fdds::DataWriterListener* listener,
                                            const fdds::StatusMask& mask) {
  fdds::Topic* t = topics_[index_of(id)];
  fdds::DataWriterQos qos;
  if (publisher_->get_datawriter_qos_from_profile(profile, qos) != ReturnCode_t::RETCODE_OK) {
    fail("creating data writer on topic '" + t->get_name() + "': no data writer profile '" +
         profile + "'");
  }
  qos.writer_resource_limits().reader_filters_allocation =
      eprosima::fastrtps::ResourceLimitedContainerConfig(0u, kMaxReaderFilters, 1u);
  fdds::DataWriter* writer = publisher_->create_datawriter(t, qos, listener, mask);
  if (writer == nullptr) {
    fail("creating data writer on topic '" + t->get_name() + "' from profile '" + profile +
         "' failed");
  }
  return *writer;
}

fdds::DataWriter& DdsContext::create_writer_in_partitions(
    TopicId id, const std::string& profile, const std::vector<std::string>& partitions) {
  fdds::PublisherQos qos = participant_->get_default_publisher_qos();
  for (const auto& p : partitions) qos.partition().push_back(p.c_str());
  fdds::Publisher* pub = participant_->create_publisher(qos);  // deleted with the participant
  if (pub == nullptr) fail("creating a publisher for topic '" + topic(id).get_name() + "' failed");
  fdds::Topic* t = topics_[index_of(id)];
  fdds::DataWriter* writer = nullptr;
  fdds::DataWriterQos qos_w;
  if (pub->get_datawriter_qos_from_profile(profile, qos_w) == ReturnCode_t::RETCODE_OK) {
    qos_w.writer_resource_limits().reader_filters_allocation =
        eprosima::fastrtps::ResourceLimitedContainerConfig(0u, kMaxReaderFilters, 1u);
    writer = pub->create_datawriter(t, qos_w);
  }
  if (writer == nullptr) {
    std::string in;
    for (const auto& p : partitions) in += (in.empty() ? "" : ", ") + p;
    fail("creating data writer on topic '" + t->get_name() + "' from profile '" + profile +
         "' in partition(s) " + (in.empty() ? std::string("<default>") : in) + " failed");
  }
  return *writer;
}

fdds::DataReader& DdsContext::create_reader(TopicId id, const std::string& profile,
                                            fdds::DataReaderListener* listener,
                                            const fdds::StatusMask& mask) {
  fdds::Topic* t = topics_[index_of(id)];
  fdds::DataReader* reader =
      subscriber_->create_datareader_with_profile(t, profile, listener, mask);
  if (reader == nullptr) {
    fail("creating data reader on topic '" + t->get_name() + "' from profile '" + profile +
         "' failed");
  }
  return *reader;
}

fdds::DataReader& DdsContext::create_vessel_reader(TopicId id, const std::string& profile,
                                                   std::uint32_t mmsi,
                                                   fdds::DataReaderListener* listener,
                                                   const fdds::StatusMask& mask) {
  fdds::Topic* t = topics_[index_of(id)];
  const std::string name = t->get_name() + "|mmsi=" + std::to_string(mmsi);
  fdds::ContentFilteredTopic* filtered =
      participant_->create_contentfilteredtopic(name, t, "mmsi = %0", {std::to_string(mmsi)});
  if (filtered == nullptr) {
    fail("creating the content-filtered topic '" + name + "' (mmsi = " + std::to_string(mmsi) +
         ") failed");
  }
  fdds::DataReader* reader =
      subscriber_->create_datareader_with_profile(filtered, profile, listener, mask);
  if (reader == nullptr) {
    fail("creating data reader on topic '" + name + "' from profile '" + profile + "' failed");
  }
  return *reader;
}

void DdsContext::delete_writer(fdds::DataWriter& writer) {
  if (publisher_->delete_datawriter(&writer) != ReturnCode_t::RETCODE_OK) {
    fail("deleting data writer failed");
  }
}

void DdsContext::delete_reader(fdds::DataReader& reader) {
  if (subscriber_->delete_datareader(&reader) != ReturnCode_t::RETCODE_OK) {
    fail("deleting data reader failed");
  }
}

}  // namespace usvfdi::dds
