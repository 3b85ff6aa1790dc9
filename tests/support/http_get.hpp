// Tests' HTTP client for the Prometheus endpoints: one GET on loopback, as a Prometheus
// server scrapes, and the value of one sample of a text page.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <sstream>
#include <string>

namespace usvfdi::testing_http {

/// The body of GET http://127.0.0.1:port/path ("" when it cannot be fetched), as a Prometheus
/// server scrapes it: one request, bounded by a receive timeout.
inline std::string get(int port, const std::string& path) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return "";
  timeval tv{5, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  std::string response;
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) {
    const std::string request =
        "GET " + path + " HTTP/1.0\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n";
    if (::send(fd, request.data(), request.size(), MSG_NOSIGNAL) ==
        static_cast<ssize_t>(request.size())) {
      char buf[4096];
      for (ssize_t n; (n = ::recv(fd, buf, sizeof buf, 0)) > 0;) response.append(buf, n);
    }
  }
  ::close(fd);
  const std::size_t body = response.find("\r\n\r\n");
  return response.rfind("HTTP/1.", 0) == 0 && response.find(" 200 ") < body &&
                 body != std::string::npos
             ? response.substr(body + 4)
             : "";
}

/// The value of the sample `name` with exactly these labels in a Prometheus text page, in
/// whatever order the page lists them (NaN when absent).
inline double sample(const std::string& page, const std::string& name,
                     const std::map<std::string, std::string>& labels) {
  std::istringstream in(page);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(name + "{", 0) != 0) continue;
    const std::size_t close = line.find("} ");
    if (close == std::string::npos) continue;
    std::map<std::string, std::string> got;
    std::istringstream pairs(line.substr(name.size() + 1, close - name.size() - 1));
    std::string pair;
    while (std::getline(pairs, pair, ',')) {
      const std::size_t eq = pair.find("=\"");
      if (eq != std::string::npos)
        got[pair.substr(0, eq)] = pair.substr(eq + 2, pair.size() - eq - 3);
    }
    if (got == labels) return std::strtod(line.c_str() + close + 2, nullptr);
  }
  return std::nan("");
}

}  // namespace usvfdi::testing_http
