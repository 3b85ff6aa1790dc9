// The bridge alert management system's side of an end-to-end test, shared by the bridge's
// (test_bridge_e2e.cpp) and the NMEA input's (test_nmea_udp_e2e.cpp): a UDP socket on
// 127.0.0.1 that receives the IEC 61162-450 datagrams `usv-fdi bridge` sends (ALF, ALC, HBT,
// ARC) and sends ACN datagrams.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "usv_fdi/nmea/alert.hpp"
#include "usv_fdi/nmea/datagram.hpp"
#include "usv_fdi/nmea/sentence.hpp"

namespace usvfdi::dds::test::bam_side {

using std::chrono::milliseconds;
using std::chrono::seconds;
using Clock = std::chrono::steady_clock;

/// A UDP socket on 127.0.0.1, port chosen by the system.
class Udp {
 public:
  Udp() : fd_(::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0)) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (fd_ < 0 || ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
      throw std::runtime_error(std::string("udp: ") + std::strerror(errno));
    }
    socklen_t len = sizeof a;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
  }
  ~Udp() { ::close(fd_); }
  Udp(const Udp&) = delete;
  Udp& operator=(const Udp&) = delete;
  int port() const { return port_; }
  std::string endpoint() const { return "127.0.0.1:" + std::to_string(port_); }

  /// Receives one datagram within `timeout`; empty on timeout.
  std::string receive(milliseconds timeout) const {
    timeval tv{static_cast<time_t>(timeout.count() / 1000),
               static_cast<suseconds_t>((timeout.count() % 1000) * 1000)};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    char buf[2048];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : std::string();
  }

  void send_to(int port, const std::string& bytes) const {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    ::sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<sockaddr*>(&a), sizeof a);
  }

 private:
  int fd_;
  int port_ = 0;
};

/// A UDP port of 127.0.0.1 free a moment ago (for the bridge to bind).
inline int free_port() {
  Udp probe;
  return probe.port();
}

/// What the bridge alert management system has received so far.
struct Bam {
  std::vector<nmea::Alf> alf;  ///< sentence 1 of each ALF message
  std::vector<nmea::Alc> alc;
  std::vector<nmea::Hbt> hbt;
  std::vector<nmea::Arc> arc;
  std::vector<std::string> bad;  ///< datagrams or lines that did not parse
  int datagrams = 0, iec450 = 0;

  void add(const std::string& bytes) {
    ++datagrams;
    const auto d = nmea::parse_datagram(bytes);
    if (!d.ok()) {
      bad.push_back(d.rejection().text);
      return;
    }
    iec450 += d.value().iec450;
    for (const auto& line : d.value().lines) {
      if (!line.ok()) {
        bad.push_back(line.rejection().text);
        continue;
      }
      const nmea::Sentence& s = line.value().sentence;
      if (s.formatter == "ALF") {
        const auto x = nmea::parse_alf(s);
        if (!x.ok()) bad.push_back(x.rejection().text);
        if (x.ok() && x.value().sentence_number == 1) alf.push_back(x.value());
      } else if (s.formatter == "ALC") {
        const auto x = nmea::parse_alc(s);
        if (x.ok()) alc.push_back(x.value());
      } else if (s.formatter == "HBT") {
        const auto x = nmea::parse_hbt(s);
        if (x.ok()) hbt.push_back(x.value());
      } else if (s.formatter == "ARC") {
        const auto x = nmea::parse_arc(s);
        if (x.ok()) arc.push_back(x.value());
      }
    }
  }

  /// The last ALF of alert `id`, or nullptr.
  const nmea::Alf* last(long id) const {
    for (auto it = alf.rbegin(); it != alf.rend(); ++it) {
      if (it->alert.id == id) return &*it;
    }
    return nullptr;
  }
  bool state_is(long id, nmea::AlertState s) const {
    const nmea::Alf* a = last(id);
    return a != nullptr && a->state == s;
  }
  bool saw(long id, nmea::AlertState s) const {
    for (const auto& a : alf) {
      if (a.alert.id == id && a.state == s) return true;
    }
    return false;
  }
  std::string dump() const {
    std::string out;
    for (const auto& a : alf) {
      out += "ALF " + std::to_string(a.alert.id) + " " +
             std::string(1, a.state ? static_cast<char>(*a.state) : '-') + " rev " +
             std::to_string(a.revision) + "\n";
    }
    for (const auto& a : arc) out += "ARC " + std::to_string(a.alert.id) + "\n";
    for (const auto& b : bad) out += "bad: " + b + "\n";
    return out;
  }
};

/// Receives into `bam` until `done()` or the timeout; true when done.
inline bool receive_until(const Udp& rx, Bam* bam, milliseconds timeout,
                          const std::function<bool()>& done) {
  const auto end = Clock::now() + timeout;
  while (!done()) {
    if (Clock::now() >= end) return false;
    const std::string d = rx.receive(milliseconds(200));
    if (!d.empty()) bam->add(d);
  }
  return true;
}

/// "$<body>*hh\r\n" with the right checksum.
inline std::string with_checksum(const std::string& body) {
  char hh[4];
  std::snprintf(hh, sizeof hh, "%02X", nmea::checksum(body));
  return "$" + body + "*" + hh + "\r\n";
}

/// An ACN datagram (IEC 61162-450, TAG source BN0001) for alert `id` of manufacturer `m`.
inline std::string acn_datagram(long id, char command, const std::string& m = "UFD") {
  nmea::Acn a;
  a.talker = "BN";
  a.alert.manufacturer = m;
  a.alert.id = id;
  a.alert.instance = 1;
  a.command = static_cast<nmea::AlertCommand>(command);
  nmea::TagBlock tag;
  tag.source = "BN0001";
  tag.line_count = 1;
  return nmea::format_iec450_datagram(tag, {nmea::format_acn(a).value()}).value();
}

/// `usv-fdi bridge`'s default alert identifiers.
constexpr long kAccel = 3001, kGyro = 3002, kUnknown = 3003;
constexpr auto V = nmea::AlertState::kActiveUnacknowledged;
constexpr auto A = nmea::AlertState::kActiveAcknowledged;
constexpr auto U = nmea::AlertState::kRectifiedUnacknowledged;
constexpr auto N = nmea::AlertState::kNormal;

}  // namespace usvfdi::dds::test::bam_side
