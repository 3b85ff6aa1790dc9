#include "fleet_view.hpp"

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

}  // namespace usvfdi::app
