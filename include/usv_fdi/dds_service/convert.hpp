// Conversions between the core's plain structs and the generated DDS types.
#pragma once

#include <cstdint>

#include "usv_fdi/core/isolation.hpp"  // IsolationParams
#include "usv_fdi/core/latch.hpp"
#include "usv_fdi/dds/types.hpp"
#include "usv_fdi/pipeline/pipeline.hpp"

namespace usvfdi::dds_service {

fdi::FaultEvent to_dds(const FaultEvent& e, std::uint32_t mmsi);
/// Returns false (and leaves *out alone) when an octet holds no known sensor/state/kind.
bool from_dds(const fdi::FaultEvent& e, FaultEvent* out);
fdi::FdiStatus to_dds(const pipeline::PipelineStatus& s, std::uint32_t mmsi,
                      const IsolationParams& p);
pipeline::InsInput from_dds(const fdi::InsSample& s);
pipeline::RudderInput from_dds(const fdi::RudderSample& s);
pipeline::SpeedInput from_dds(const fdi::SpeedSample& s);
/// An unknown sensor octet is passed on as is: the isolation thread refuses it with a reason.
pipeline::AckInput from_dds(const fdi::FaultAck& a);

}  // namespace usvfdi::dds_service
