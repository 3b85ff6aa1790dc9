// NMEA 0183 / IEC 61162-450 over UDP (include/usv_fdi/nmea_udp/udp.hpp).
#include "usv_fdi/nmea_udp/udp.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>

#include "usv_fdi/nmea/datagram.hpp"

namespace usvfdi::nmea_udp {

namespace {

constexpr std::size_t kMaxExamples = 8;
/// Read buffer: larger than any UDP payload, so that an over-long datagram is seen whole (and
/// refused as too long) rather than cut.
constexpr std::size_t kReadBuffer = 65536;
/// Datagrams read by one poll() at most.
constexpr int kMaxPerPoll = 256;

in_addr to_in_addr(const std::string& address) {
  in_addr a{};
  if (::inet_pton(AF_INET, address.c_str(), &a) != 1) {
    throw std::invalid_argument("'" + address + "' is not an IPv4 address");
  }
  return a;
}

std::string system_error(const std::string& what) { return what + ": " + std::strerror(errno); }

}  // namespace

Endpoint parse_endpoint(const std::string& text) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == text.size()) {
    throw std::invalid_argument("'" + text + "' is not ADDRESS:PORT (e.g. 239.192.0.1:60001)");
  }
  Endpoint e;
  e.address = text.substr(0, colon);
  to_in_addr(e.address);
  const std::string p = text.substr(colon + 1);
  std::size_t used = 0;
  unsigned long port = 0;
  try {
    port = std::stoul(p, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != p.size() || port > 65535) {
    throw std::invalid_argument("'" + text + "': the port must be 0..65535");
  }
  e.port = static_cast<std::uint16_t>(port);
  return e;
}

bool is_multicast(const std::string& address) {
  return IN_MULTICAST(ntohl(to_in_addr(address).s_addr));
}

std::string DecoderStats::describe() const {
  std::string out;
  for (const auto& [reason, n] : reasons) {
    if (!out.empty()) out += ", ";
    out += std::to_string(n) + " " + reason;
  }
  return out;
}

DatagramDecoder::DatagramDecoder(const nmea::AssemblerConfig& config)
    : assembler_(config), latest_t_(std::numeric_limits<double>::quiet_NaN()) {}

void DatagramDecoder::refuse(const std::string& reason, const std::string& text) {
  ++stats_.bad;
  ++stats_.reasons[reason];
  if (examples_.size() < kMaxExamples) examples_.push_back(reason + ": " + text);
}

std::vector<std::string> DatagramDecoder::take_examples() {
  std::vector<std::string> out;
  out.swap(examples_);
  return out;
}

void DatagramDecoder::see_line_count(const std::string& source, std::int64_t n) {
  const auto it = line_counts_.find(source);
  if (it != line_counts_.end()) {
    // n: runs 1..999 and wraps; a step of d > 1 loses d - 1 lines. A repeat (d = 0) or a step
    // back (d > 500) is a restarted or re-ordered sender, not a loss.
    const std::int64_t d = ((n - it->second) % 999 + 999) % 999;
    if (d > 1 && d <= 500) stats_.lost_lines += static_cast<std::uint64_t>(d - 1);
  }
  line_counts_[source] = n;
}

void DatagramDecoder::add(std::string_view bytes, double receive_time) {
  ++stats_.datagrams;
  if (first_receive_ < 0.0) first_receive_ = receive_time;
  const nmea::Result<nmea::Datagram> parsed = nmea::parse_datagram(bytes);
  if (!parsed) {
    refuse(nmea::to_string(parsed.rejection().reason), "datagram: " + parsed.rejection().text);
    return;
  }
  std::optional<double> datagram_t;  // the c: of an earlier line of this datagram
  for (const nmea::Result<nmea::TaggedSentence>& line : parsed.value().lines) {
    ++stats_.lines;
    if (!line) {
      refuse(nmea::to_string(line.rejection().reason), line.rejection().text);
      continue;
    }
    const nmea::TaggedSentence& ts = line.value();
    if (ts.tag) {
      if (ts.tag->line_count) see_line_count(ts.tag->source.value_or(""), *ts.tag->line_count);
      if (ts.tag->unix_time_ms) {
        if (first_tag_ms_ < 0) first_tag_ms_ = *ts.tag->unix_time_ms;
        // Exact in a double: a difference of integers in milliseconds.
        datagram_t = static_cast<double>(*ts.tag->unix_time_ms - first_tag_ms_) / 1000.0;
      }
    }
    const double t = datagram_t ? *datagram_t : receive_time - first_receive_;
    const nmea::InputResult r = assembler_.add_sentence(t, ts.sentence);
    const std::string& f = ts.sentence.formatter;
    switch (r.use) {
      case nmea::InputUse::kUsed:
        ++stats_.used;
        latest_t_ = t;
        break;
      case nmea::InputUse::kNotValid:
        ++stats_.used;
        ++stats_.not_valid;
        latest_t_ = t;
        break;
      case nmea::InputUse::kNotAnInput:
        ++stats_.ignored;
        break;
      case nmea::InputUse::kRefused:
        refuse(nmea::to_string(r.rejection.reason), f + ": " + r.rejection.text);
        break;
      case nmea::InputUse::kOutOfOrder:
        refuse("time going back", f + ": t = " + std::to_string(t) + " before the latest line's");
        break;
    }
  }
}

std::vector<nmea::StaleInput> DatagramDecoder::stale() const {
  if (std::isnan(latest_t_)) return {};
  return assembler_.stale(latest_t_);
}

UdpListener::UdpListener(const Endpoint& endpoint, const std::string& interface_address,
                         int receive_buffer, const std::string& what)
    : buffer_(kReadBuffer) {
  const in_addr address = to_in_addr(endpoint.address);
  multicast_ = IN_MULTICAST(ntohl(address.s_addr));
  in_addr iface{};
  iface.s_addr = htonl(INADDR_ANY);
  if (!interface_address.empty()) iface = to_in_addr(interface_address);
  const std::string where = endpoint.address + ":" + std::to_string(endpoint.port);

  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd_ < 0) throw std::runtime_error(system_error(what + ": socket"));
  const auto fail = [this](const std::string& what) {
    const std::string msg = system_error(what);
    ::close(fd_);
    fd_ = -1;
    throw std::runtime_error(msg);
  };
  const int one = 1;
  if (::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0) {
    fail(what + " " + where + ": SO_REUSEADDR");
  }
  if (receive_buffer > 0) {
    // A short burst must not overflow the queue while the thread is busy; the kernel caps
    // the request at net.core.rmem_max (the granted size is logged).
    (void)::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer, sizeof receive_buffer);
  }
  socklen_t len = sizeof rcvbuf_;
  if (::getsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf_, &len) != 0) rcvbuf_ = 0;
  sockaddr_in bind_to{};
  bind_to.sin_family = AF_INET;
  bind_to.sin_port = htons(endpoint.port);
  // Multicast: bound to the group, so that only its datagrams arrive (not those of another
  // group on the same port); unicast: the local address given.
  bind_to.sin_addr = address;
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&bind_to), sizeof bind_to) != 0) {
    fail(what + ": cannot bind " + where);
  }
  if (multicast_) {
    ip_mreq m{};
    m.imr_multiaddr = address;
    m.imr_interface = iface;
    if (::setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &m, sizeof m) != 0) {
      fail(what + ": cannot join the multicast group " + where + " on " +
           (interface_address.empty() ? std::string("any interface") : interface_address));
    }
  }
  sockaddr_in bound{};
  socklen_t blen = sizeof bound;
  port_ = ::getsockname(fd_, reinterpret_cast<sockaddr*>(&bound), &blen) == 0
              ? ntohs(bound.sin_port)
              : endpoint.port;
  const std::string at = endpoint.address + ":" + std::to_string(port_);
  description_ = multicast_ ? "multicast group " + at + " on " +
                                  (interface_address.empty() ? std::string("any interface")
                                                             : interface_address)
                            : "unicast " + at;
}

UdpListener::~UdpListener() {
  if (fd_ >= 0) ::close(fd_);
}

int UdpListener::read(
    int timeout_ms, const std::function<void(std::string_view, const std::string&)>& on_datagram) {
  pollfd p{};
  p.fd = fd_;
  p.events = POLLIN;
  const int ready = ::poll(&p, 1, timeout_ms);
  if (ready < 0) return errno == EINTR ? 0 : -1;
  if (ready == 0) return 0;
  int n = 0;
  // Bounded, so that a flood cannot keep the caller from handing samples on or stopping.
  while (n < kMaxPerPoll) {
    sockaddr_in from{};
    socklen_t from_len = sizeof from;
    const ssize_t got = ::recvfrom(fd_, buffer_.data(), buffer_.size(), 0,
                                   reinterpret_cast<sockaddr*>(&from), &from_len);
    if (got < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return n;
      return n > 0 ? n : -1;
    }
    char sender[INET_ADDRSTRLEN] = "?";
    ::inet_ntop(AF_INET, &from.sin_addr, sender, sizeof sender);
    on_datagram(std::string_view(buffer_.data(), static_cast<std::size_t>(got)), sender);
    ++n;
  }
  return n;
}

NmeaUdpReceiver::NmeaUdpReceiver(const ReceiverConfig& config)
    : decoder_(config.assembler),
      socket_(config.endpoint, config.interface_address, config.receive_buffer, "NMEA input") {}

int NmeaUdpReceiver::poll(int timeout_ms) {
  return socket_.read(timeout_ms, [this](std::string_view bytes, const std::string&) {
    const double now =
        std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
    decoder_.add(bytes, now);
  });
}

NmeaUdpSender::NmeaUdpSender(const Endpoint& to, const std::string& interface_address, int ttl) {
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(to.port);
  addr.sin_addr = to_in_addr(to.address);
  const bool multicast = IN_MULTICAST(ntohl(addr.sin_addr.s_addr));
  in_addr iface{};
  if (!interface_address.empty()) iface = to_in_addr(interface_address);
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error(system_error("NMEA output: socket"));
  const auto fail = [this](const std::string& what) {
    const std::string msg = system_error(what);
    ::close(fd_);
    fd_ = -1;
    throw std::runtime_error(msg);
  };
  if (multicast) {
    const unsigned char t = static_cast<unsigned char>(ttl < 0 ? 0 : ttl > 255 ? 255 : ttl);
    const unsigned char loop = 1;
    if (::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_TTL, &t, sizeof t) != 0) {
      fail("NMEA output: IP_MULTICAST_TTL");
    }
    if (::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof loop) != 0) {
      fail("NMEA output: IP_MULTICAST_LOOP");
    }
    if (!interface_address.empty() &&
        ::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_IF, &iface, sizeof iface) != 0) {
      fail("NMEA output: IP_MULTICAST_IF " + interface_address);
    }
  }
  to_.resize(sizeof addr);
  std::memcpy(to_.data(), &addr, sizeof addr);
}

NmeaUdpSender::~NmeaUdpSender() {
  if (fd_ >= 0) ::close(fd_);
}

bool NmeaUdpSender::send(std::string_view bytes) {
  const ssize_t n =
      ::sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(to_.data()),
               static_cast<socklen_t>(to_.size()));
  return n == static_cast<ssize_t>(bytes.size());
}

}  // namespace usvfdi::nmea_udp
