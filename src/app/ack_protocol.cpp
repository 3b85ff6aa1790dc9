#include "ack_protocol.hpp"

#include <sstream>
#include <stdexcept>

namespace usvfdi::app {

bool parse_ack(const std::string& spec, AckRequest* out, std::string* why) {
  std::stringstream ss(spec);
  std::string m, s, q;
  if (!std::getline(ss, m, ':') || !std::getline(ss, s, ':') || !std::getline(ss, q) || m.empty() ||
      q.empty()) {
    *why = "--ack " + spec + ": expected MMSI:SENSOR:SEQUENCE (e.g. 257000001:gyro:3)";
    return false;
  }
  Sensor sensor;
  if (!parse_sensor(s, &sensor)) {
    *why = "--ack " + spec + ": sensor '" + s + "' is not accelerometer, gyro or unknown";
    return false;
  }
  try {
    std::size_t pm = 0, pq = 0;
    const unsigned long mmsi = std::stoul(m, &pm);
    const unsigned long long seq = std::stoull(q, &pq);
    if (pm != m.size() || pq != q.size() || mmsi == 0 || mmsi > 999999999ul || seq == 0) {
      throw std::invalid_argument(spec);
    }
    out->mmsi = static_cast<std::uint32_t>(mmsi);
    out->sensor = sensor;
    out->sequence = seq;
  } catch (const std::exception&) {
    *why = "--ack " + spec + ": MMSI (1..999999999) and SEQUENCE (>= 1) must be integers";
    return false;
  }
  return true;
}

bool ack_confirmed(const AckRequest& ack, const Row* row) {
  return row != nullptr && row->ev.sequence > ack.sequence &&
         (row->ev.state == FaultState::kActiveAcknowledged ||
          row->ev.state == FaultState::kAcknowledged);
}

bool ack_already_past(const AckRequest& ack, const Row* row) {
  return row != nullptr && row->ev.sequence > ack.sequence;
}

std::string refusal_reason(const AckRequest& ack, const Row* row) {
  if (row == nullptr) return "no such fault instance is latched on this domain/partition";
  const std::uint64_t cur = row->ev.sequence;
  std::string state = " (current #" + std::to_string(cur) + ", " + to_string(row->ev.state) + ")";
  if (ack.sequence < cur) return "stale sequence" + state;
  if (ack.sequence > cur) return "unknown sequence" + state;
  if (row->ev.state != FaultState::kRaised && row->ev.state != FaultState::kClearedUnacknowledged) {
    return "nothing to acknowledge" + state;
  }
  return "no confirmation from the sidecar" + state;
}

std::vector<std::string> ack_partitions(const std::vector<std::string>& mine, std::uint32_t mmsi) {
  std::vector<std::string> out;
  for (const std::string& p : mine) {
    const std::string tag = "vessel-*";
    const bool wildcard =
        p.size() >= tag.size() && p.compare(p.size() - tag.size(), tag.size(), tag) == 0;
    out.push_back(wildcard ? p.substr(0, p.size() - 1) + std::to_string(mmsi) : p);
  }
  return out;
}

}  // namespace usvfdi::app
