#include "fleet_view.hpp"

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

#include <algorithm>
#include <cstdint>
#include <sstream>

#include "usv_fdi/core/text.hpp"

namespace usvfdi::app {

std::string writer_name(const dds::DdsContext& ctx, const fdds::InstanceHandle_t& h) {
  std::ostringstream os;
  os << eprosima::fastrtps::rtps::iHandle2GUID(h);
  const auto w = ctx.peers().writer(h);
  if (w) {
    const std::string cn = dds::common_name(w->subject);
    if (!cn.empty()) os << " (identity " << cn << ")";
    std::string parts;
    for (const auto& p : w->partitions) parts += (parts.empty() ? "" : ",") + p;
    os << " [partition " << (parts.empty() ? std::string("<default>") : parts) << "]";
  }
  return escape_text(os.str());  // names and partitions come from the peer
}

int unicast_discovery_limit(const fdds::DomainParticipantQos& qos) {
  namespace rtps = eprosima::fastrtps::rtps;
  const auto& builtin = qos.wire_protocol().builtin;
  // Multicast discovery (the builtin UDPv4 and shared-memory transports, a multicast locator)
  // and discovery servers reach every participant; only unicast SIMPLE discovery is bounded.
  if (builtin.discovery_config.discoveryProtocol != rtps::DiscoveryProtocol_t::SIMPLE ||
      qos.transport().use_builtin_transports || builtin.initialPeersList.empty() ||
      !builtin.metatrafficMulticastLocatorList.empty()) {
    return 0;
  }
  int limit = 0;
  for (const auto& t : qos.transport().user_transports) {
    if (dynamic_cast<const eprosima::fastdds::rtps::UDPv4TransportDescriptor*>(t.get()) ==
        nullptr) {
      return 0;  // shared memory (or another transport) next to it: not bounded here
    }
    limit = std::max(limit, static_cast<int>(t->max_initial_peers_range()));
  }
  // A participant whose discovery port is taken tries the next participant id's, at most
  // mutation_tries times: on one host no more participants than that get a port of their own.
  return std::min(limit,
                  static_cast<int>(std::min<std::uint32_t>(builtin.mutation_tries, 1000000)));
}

}  // namespace usvfdi::app
