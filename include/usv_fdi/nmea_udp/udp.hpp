// NMEA 0183 / IEC 61162-450 over UDP: the sidecar's live input adapter (issue 12, section 2)
// and the simulator's sender. POSIX sockets; the nmea library does the parsing and the
// assembling (SampleAssembler::add_sentence), nothing is re-implemented here.
//
// Receiving: a socket bound to the port, joined (IP_ADD_MEMBERSHIP) to the multicast group on
// the given interface, or bound to a unicast address (any address not in 224.0.0.0/4;
// "0.0.0.0": every local address). SO_REUSEADDR, so several listeners may share a group and
// port on one host. Every datagram is read as an IEC 61162-450 sentence datagram ("UdPbC\0"
// and lines) or as plain NMEA 0183 (one or more lines, CR LF or LF); each line may carry a TAG
// block. Checksums are verified, any talker is accepted, status V invalidates a value.
//
// Time of a line (the engine's time base), in seconds since the first datagram this decoder
// read, as the log replay counts from the log's first c: (UNIX seconds would lose the fraction
// in the 9 significant digits of the JSON outputs): the c: of its TAG block less the first c:
// seen; else the c: of an earlier line of the same datagram; else the datagram's receive time
// on the monotonic clock (steady_clock) less the first datagram's. The time does not depend on
// when datagrams arrive as long as the sender gives c:. The two bases do not mix well: a
// sender with c: and one without on the same group make the time jump (lines counted as "time
// going back"). A restarted sidecar starts a new time base at its first datagram.
//
// Losses: IEC 61162-450 senders number their lines (TAG n:, 1..999 per source s:); a gap in a
// source's numbers is counted as lost lines (the samples hold the last value meanwhile, up to
// the assembler's max_age_s: a lost datagram is a gap, never a fault).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "usv_fdi/nmea/assembler.hpp"

namespace usvfdi::nmea_udp {

/// The default IEC 61162-450 style transmission group and port (MISC).
constexpr const char* kDefaultGroup = "239.192.0.1";
constexpr std::uint16_t kDefaultPort = 60001;

struct Endpoint {
  std::string address = kDefaultGroup;  ///< dotted IPv4
  std::uint16_t port = kDefaultPort;
};

/// "239.192.0.1:60001" (or "127.0.0.1:60001"). Throws std::invalid_argument naming the text.
Endpoint parse_endpoint(const std::string& text);
/// True for an IPv4 address in 224.0.0.0/4; throws std::invalid_argument if not an address.
bool is_multicast(const std::string& address);

struct ReceiverConfig {
  Endpoint endpoint;              ///< group joined (multicast) or address bound (unicast)
  std::string interface_address;  ///< multicast: the interface to join on ("" : any)
  int receive_buffer = 4 << 20;   ///< SO_RCVBUF asked for [bytes] (the kernel may cap it)
  nmea::AssemblerConfig assembler;
};

/// Counters since start.
struct DecoderStats {
  std::uint64_t datagrams = 0;   ///< received
  std::uint64_t lines = 0;       ///< lines in them
  std::uint64_t used = 0;        ///< ROT, RSA, VBW, VTG read into the samples
  std::uint64_t not_valid = 0;   ///< of those, with status V (or an empty value)
  std::uint64_t ignored = 0;     ///< other sentences (HDT, THS, proprietary, ...)
  std::uint64_t bad = 0;         ///< refused lines and datagrams: the sum of `reasons`
  std::uint64_t lost_lines = 0;  ///< gaps in the TAG line counts n: of each source
  std::map<std::string, std::uint64_t> reasons;  ///< "checksum mismatch", "bad header", ...
  /// "3 checksum mismatch, 1 bad header" ("" : none).
  std::string describe() const;
};

/// Datagram bytes and their receive time in, assembled samples out. No socket: the unit the
/// tests drive directly, and what NmeaUdpReceiver feeds.
class DatagramDecoder {
 public:
  /// Throws std::invalid_argument for a bad assembler configuration.
  explicit DatagramDecoder(const nmea::AssemblerConfig& config);
  /// One datagram; receive_time [s, monotonic]. Never throws on bad input.
  void add(std::string_view bytes, double receive_time);
  /// The samples completed since the last call, oldest first.
  std::vector<nmea::AssembledSample> take() { return assembler_.take(); }
  /// The sentences that have stopped, at the latest line's time.
  std::vector<nmea::StaleInput> stale() const;
  /// The latest line's time [s] (NaN before the first).
  double latest_time() const { return latest_t_; }
  /// The first c: read [ms since 1970-01-01 UTC]: t = 0 of the TAG time base (-1: none yet).
  std::int64_t first_tag_ms() const { return first_tag_ms_; }
  const DecoderStats& stats() const { return stats_; }
  /// What was refused since the last call ("checksum mismatch: ..."), at most `max` kept.
  std::vector<std::string> take_examples();

 private:
  void refuse(const std::string& reason, const std::string& text);
  void see_line_count(const std::string& source, std::int64_t n);
  nmea::SampleAssembler assembler_;
  DecoderStats stats_;
  double latest_t_;
  std::int64_t first_tag_ms_ = -1;
  double first_receive_ = -1.0;                      ///< [s, monotonic] (-1: no datagram yet)
  std::map<std::string, std::int64_t> line_counts_;  ///< latest n: per TAG source s:
  std::vector<std::string> examples_;
};

/// A receiving UDP socket: bound to a multicast group (joined on an interface) or a unicast
/// address, non-blocking. Not thread-safe: one thread polls it.
class UdpListener {
 public:
  /// Opens, binds and joins; `what` names it in errors ("NMEA input"). Throws
  /// std::runtime_error naming the address and the system's reason, std::invalid_argument for a
  /// bad address.
  UdpListener(const Endpoint& endpoint, const std::string& interface_address, int receive_buffer,
              const std::string& what);
  ~UdpListener();
  UdpListener(const UdpListener&) = delete;
  UdpListener& operator=(const UdpListener&) = delete;

  /// Waits up to timeout_ms for a datagram (poll), then hands the datagrams waiting (at most
  /// 256) to `on_datagram(bytes, sender address)`. Returns the datagrams read; -1 on a socket
  /// error (errno kept; EINTR is 0).
  int read(int timeout_ms,
           const std::function<void(std::string_view, const std::string&)>& on_datagram);
  /// The receive buffer the kernel granted [bytes].
  int receive_buffer() const { return rcvbuf_; }
  bool multicast() const { return multicast_; }
  /// "multicast group 239.192.0.1:60001 on 127.0.0.1" / "unicast 127.0.0.1:60001".
  const std::string& describe() const { return description_; }
  /// The port bound (useful with port 0: the kernel's choice).
  std::uint16_t port() const { return port_; }

 private:
  int fd_ = -1;
  int rcvbuf_ = 0;
  bool multicast_ = false;
  std::uint16_t port_ = 0;
  std::string description_;
  std::vector<char> buffer_;
};

/// The NMEA input: a UdpListener whose datagrams go to a DatagramDecoder.
class NmeaUdpReceiver {
 public:
  /// Throws as UdpListener, and std::invalid_argument for a bad assembler configuration.
  explicit NmeaUdpReceiver(const ReceiverConfig& config);

  /// Waits up to timeout_ms for a datagram, then reads the datagrams waiting (at most 256) into
  /// the decoder. Returns the datagrams read; -1 on a socket error (errno kept; EINTR is 0).
  int poll(int timeout_ms);
  DatagramDecoder& decoder() { return decoder_; }
  const DatagramDecoder& decoder() const { return decoder_; }
  int receive_buffer() const { return socket_.receive_buffer(); }
  bool multicast() const { return socket_.multicast(); }
  const std::string& describe() const { return socket_.describe(); }
  std::uint16_t port() const { return socket_.port(); }

 private:
  DatagramDecoder decoder_;
  UdpListener socket_;
};

/// Sends datagrams to a multicast group (or a unicast address).
class NmeaUdpSender {
 public:
  /// interface_address: the multicast interface (IP_MULTICAST_IF; "" : the kernel's choice);
  /// ttl: IP_MULTICAST_TTL (0: this host only, 1: the local network); multicast loop on, so
  /// listeners on this host receive. Throws std::runtime_error / std::invalid_argument.
  NmeaUdpSender(const Endpoint& to, const std::string& interface_address, int ttl);
  ~NmeaUdpSender();
  NmeaUdpSender(const NmeaUdpSender&) = delete;
  NmeaUdpSender& operator=(const NmeaUdpSender&) = delete;
  /// Sends one datagram; false (errno kept) when the system refuses it.
  bool send(std::string_view bytes);

 private:
  int fd_ = -1;
  std::vector<unsigned char> to_;  ///< sockaddr_in
};

}  // namespace usvfdi::nmea_udp
