#include "usv_fdi/dds/peers.hpp"

#include <fastdds/rtps/builtin/data/ParticipantProxyData.h>
#include <fastdds/rtps/builtin/data/WriterProxyData.h>
#include <fastdds/rtps/participant/ParticipantDiscoveryInfo.h>
#include <fastdds/rtps/writer/WriterDiscoveryInfo.h>

#include <cctype>
#include <cstdint>

namespace usvfdi::dds {

namespace rtps = eprosima::fastrtps::rtps;

void PeerDirectory::on_participant_discovery(eprosima::fastdds::dds::DomainParticipant*,
                                             rtps::ParticipantDiscoveryInfo&& info) {
  const rtps::GuidPrefix_t prefix = info.info.m_guid.guidPrefix;
  std::lock_guard<std::mutex> lock(m_);
  if (info.status == rtps::ParticipantDiscoveryInfo::REMOVED_PARTICIPANT ||
      info.status == rtps::ParticipantDiscoveryInfo::DROPPED_PARTICIPANT) {
    subjects_.erase(prefix);
    participants_.erase(prefix);
    return;
  }
  if (info.status == rtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT ||
      info.status == rtps::ParticipantDiscoveryInfo::CHANGED_QOS_PARTICIPANT) {
    participants_.insert(prefix);
  }
#if HAVE_SECURITY
  // The identity token the participant announced; under DDS Security only a participant that
  // passed the PKI-DH handshake with a certificate of the identity CA is discovered at all, and its
  // GUID prefix is derived from its certificate's subject (checked in the handshake).
  const std::string* sn =
      rtps::DataHolderHelper::find_property_value(info.info.identity_token_, "dds.cert.sn");
  if (sn != nullptr) subjects_[prefix] = *sn;
#endif
}

void PeerDirectory::on_publisher_discovery(eprosima::fastdds::dds::DomainParticipant*,
                                           rtps::WriterDiscoveryInfo&& info) {
  std::lock_guard<std::mutex> lock(m_);
  const rtps::GUID_t guid = info.info.guid();
  if (info.status == rtps::WriterDiscoveryInfo::REMOVED_WRITER) {
    writers_.erase(guid);
    return;
  }
  Writer w;
  w.topic = info.info.topicName().to_string();
  w.partitions = info.info.m_qos.m_partition.names();
  writers_[guid] = std::move(w);
}

std::optional<PeerDirectory::Writer> PeerDirectory::writer(
    const rtps::InstanceHandle_t& publication) const {
  const rtps::GUID_t guid = rtps::iHandle2GUID(publication);
  std::lock_guard<std::mutex> lock(m_);
  const auto it = writers_.find(guid);
  if (it == writers_.end()) return std::nullopt;
  Writer w = it->second;
  const auto s = subjects_.find(guid.guidPrefix);
  if (s != subjects_.end()) w.subject = s->second;
  return w;
}

std::size_t PeerDirectory::participant_count() const {
  std::lock_guard<std::mutex> lock(m_);
  return participants_.size();
}

std::string PeerDirectory::subject_of(const rtps::InstanceHandle_t& publication) const {
  const rtps::GUID_t guid = rtps::iHandle2GUID(publication);
  std::lock_guard<std::mutex> lock(m_);
  const auto s = subjects_.find(guid.guidPrefix);
  return s == subjects_.end() ? std::string() : s->second;
}

std::string common_name(const std::string& subject) {
  // OpenSSL's one-line form, as Fast DDS's PKI-DH announces it: "/C=NO/O=fleet/OU=shore/CN=shore".
  if (!subject.empty() && subject[0] == '/') {
    const std::size_t at = subject.rfind("/CN=");
    if (at == std::string::npos) return std::string();
    const std::size_t end = subject.find('/', at + 4);
    return subject.substr(at + 4, end == std::string::npos ? std::string::npos : end - at - 4);
  }
  // RFC 2253: attributes separated by unescaped ',' (or '+' within one RDN), '\' escapes.
  std::size_t i = 0;
  while (i < subject.size()) {
    std::size_t end = i;
    std::string value;
    bool esc = false;
    for (; end < subject.size(); ++end) {
      const char c = subject[end];
      if (esc) {
        value += c;
        esc = false;
      } else if (c == '\\') {
        esc = true;
      } else if (c == ',' || c == '+') {
        break;
      } else {
        value += c;
      }
    }
    std::size_t k = 0;
    while (k < value.size() && value[k] == ' ') ++k;
    if (value.compare(k, 3, "CN=") == 0) return value.substr(k + 3);
    i = end + 1;
  }
  return std::string();
}

std::string operator_of(const std::string& subject, const std::string& claimed) {
  std::string cn = common_name(subject);
  if (cn.empty()) cn = "?";
  return claimed.empty() || claimed == cn ? cn : cn + ":" + claimed;
}

std::uint32_t vessel_of_partition(const std::string& partition) {
  static const std::string kTag = "vessel-";
  const std::size_t at = partition.rfind(kTag);
  if (at == std::string::npos) return 0;
  const std::string digits = partition.substr(at + kTag.size());
  if (digits.empty() || digits.size() > 9 || digits[0] == '0') return 0;
  std::uint32_t m = 0;
  for (const char c : digits) {
    if (!std::isdigit(static_cast<unsigned char>(c))) return 0;
    m = m * 10 + static_cast<std::uint32_t>(c - '0');
  }
  return m;
}

std::uint32_t vessel_of_writer(const std::vector<std::string>& partitions) {
  return partitions.size() == 1 ? vessel_of_partition(partitions.front()) : 0;
}

}  // namespace usvfdi::dds
