#include "usv_fdi/dds_service/journal.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <set>

#include "usv_fdi/io/jsonl.hpp"

namespace usvfdi::dds_service {
namespace {

constexpr const char* kFormat = "usv-fdi fault state";
constexpr const char* kChecksumLine = "  \"checksum\": \"fnv1a64:";

std::uint64_t fnv1a64(const std::string& s) {
  std::uint64_t h = 14695981039346656037ull;  // FNV-1a 64 offset basis
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::string hex64(std::uint64_t x) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(x));
  return buf;
}

struct Bad : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string where(const YAML::Node& n) { return "line " + std::to_string(n.Mark().line + 1); }

YAML::Node need(const YAML::Node& map, const std::string& key, const std::string& ctx) {
  for (const auto& kv : map) {
    if (kv.first.Scalar() == key) return kv.second;
  }
  throw Bad(ctx + ": \"" + key + "\" is missing");
}

double real(const YAML::Node& n, const std::string& key) {
  if (n.IsNull()) return std::nan("");
  if (!n.IsScalar()) throw Bad(where(n) + ": \"" + key + "\" must be a number or null");
  try {
    return n.as<double>();
  } catch (const YAML::Exception&) {
    throw Bad(where(n) + ": \"" + key + "\" = " + n.Scalar() + " is not a number");
  }
}

std::uint64_t integer(const YAML::Node& n, const std::string& key) {
  if (!n.IsScalar()) throw Bad(where(n) + ": \"" + key + "\" must be an integer");
  const std::string& s = n.Scalar();
  if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos || s.size() > 19) {
    throw Bad(where(n) + ": \"" + key + "\" = " + s + " is not a non-negative integer");
  }
  return std::stoull(s);
}

std::string text(const YAML::Node& n, const std::string& key) {
  if (!n.IsScalar()) throw Bad(where(n) + ": \"" + key + "\" must be a string");
  return n.Scalar();
}

FaultEvent instance(const YAML::Node& n) {
  if (!n.IsMap()) throw Bad(where(n) + ": an instance must be an object");
  static const std::set<std::string> keys = {
      "sensor",    "state",          "kind",  "sequence", "c_a",     "c_g",        "statistic",
      "threshold", "detection_time", "stamp", "a",        "message", "onset_time", "incarnation"};
  for (const auto& kv : n) {
    if (!keys.count(kv.first.Scalar())) {
      throw Bad(where(kv.first) + ": unknown field \"" + kv.first.Scalar() + "\"");
    }
  }
  const std::string ctx = where(n) + ": instance";
  FaultEvent e;
  const std::string sensor = text(need(n, "sensor", ctx), "sensor");
  if (!parse_sensor(sensor, &e.sensor)) throw Bad(ctx + ": unknown sensor \"" + sensor + "\"");
  const std::string state = text(need(n, "state", ctx), "state");
  if (!parse_fault_state(state, &e.state)) throw Bad(ctx + ": unknown state \"" + state + "\"");
  const std::string kind = text(need(n, "kind", ctx), "kind");
  if (!parse_fault_kind(kind, &e.kind)) throw Bad(ctx + ": unknown kind \"" + kind + "\"");
  e.sequence = integer(need(n, "sequence", ctx), "sequence");
  if (e.sequence == 0) throw Bad(ctx + ": sequence 0 (sequences start at 1)");
  e.c_a = real(need(n, "c_a", ctx), "c_a");
  e.c_g = real(need(n, "c_g", ctx), "c_g");
  e.statistic = real(need(n, "statistic", ctx), "statistic");
  e.threshold = real(need(n, "threshold", ctx), "threshold");
  e.onset_time = real(need(n, "onset_time", ctx), "onset_time");
  e.detection_time = real(need(n, "detection_time", ctx), "detection_time");
  e.t = real(need(n, "stamp", ctx), "stamp");
  const YAML::Node a = need(n, "a", ctx);
  if (!a.IsSequence() || a.size() != 4) throw Bad(where(a) + ": \"a\" must be a list of 4 numbers");
  for (int i = 0; i < 4; ++i) e.A(i / 2, i % 2) = real(a[i], "a");
  e.message = text(need(n, "message", ctx), "message");
  // Optional: files written before incarnations existed have none (0).
  for (const auto& kv : n) {
    if (kv.first.Scalar() == "incarnation") e.incarnation = integer(kv.second, "incarnation");
  }
  return e;
}

std::string utc_stamp(double unix_s, const char* format) {
  const std::time_t t = static_cast<std::time_t>(unix_s);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, format, &tm);
  return buf;
}

}  // namespace

std::string StateJournal::path_for(const std::string& dir, std::uint32_t mmsi) {
  return (std::filesystem::path(dir) / ("usv-fdi-" + std::to_string(mmsi) + ".state.json"))
      .string();
}

std::string StateJournal::serialise(std::uint32_t mmsi, const std::vector<FaultEvent>& events,
                                    double written) {
  std::string s = "{\n  \"format\": \"" + std::string(kFormat) +
                  "\",\n  \"version\": " + std::to_string(kVersion) +
                  ",\n  \"mmsi\": " + std::to_string(mmsi) +
                  ",\n  \"written\": " + io::json_number(written, 17) + ",\n  \"instances\": [";
  for (std::size_t i = 0; i < events.size(); ++i) {
    const FaultEvent& e = events[i];
    s += i == 0 ? "\n" : ",\n";
    s += "    {" + io::fault_event_fields(e, 17) + "}";
  }
  s += events.empty() ? "],\n" : "\n  ],\n";
  return s + kChecksumLine + hex64(fnv1a64(s)) + "\"\n}\n";
}

bool StateJournal::parse(const std::string& text_in, std::uint32_t mmsi, Contents* out,
                         std::string* error) {
  try {
    // The checksum first: it tells a damaged file from one this version cannot read.
    const auto at = text_in.rfind(std::string("\n") + kChecksumLine);
    if (at == std::string::npos) {
      throw Bad(text_in.empty() ? "the file is empty"
                                : "no checksum line: the file is truncated or not a state file");
    }
    const std::string body = text_in.substr(0, at + 1);
    const std::size_t hex_at = at + 1 + std::strlen(kChecksumLine);
    const std::string stored = text_in.substr(hex_at, 16);
    const std::string actual = hex64(fnv1a64(body));
    if (stored != actual) {
      throw Bad("checksum mismatch (file says fnv1a64:" + stored +
                ", content is fnv1a64:" + actual + "): the file was damaged or edited");
    }
    YAML::Node root;
    try {
      root = YAML::Load(text_in);
    } catch (const YAML::ParserException& e) {
      throw Bad("not valid JSON at line " + std::to_string(e.mark.line + 1) + ", column " +
                std::to_string(e.mark.column + 1) + ": " + e.msg);
    }
    if (!root.IsMap()) throw Bad("not a JSON object");
    const std::string ctx = "top level";
    const std::string format = text(need(root, "format", ctx), "format");
    if (format != kFormat) throw Bad("\"format\" is \"" + format + "\", not \"" + kFormat + "\"");
    const std::uint64_t version = integer(need(root, "version", ctx), "version");
    if (version != static_cast<std::uint64_t>(kVersion)) {
      throw Bad("version " + std::to_string(version) + " (this usv-fdi reads version " +
                std::to_string(kVersion) + " only)");
    }
    const std::uint64_t file_mmsi = integer(need(root, "mmsi", ctx), "mmsi");
    if (file_mmsi != mmsi) {
      throw Bad("the file is for MMSI " + std::to_string(file_mmsi) + ", this sidecar watches " +
                std::to_string(mmsi));
    }
    Contents c;
    c.written = real(need(root, "written", ctx), "written");
    const YAML::Node list = need(root, "instances", ctx);
    if (!list.IsSequence()) throw Bad(where(list) + ": \"instances\" must be a list");
    std::set<int> seen;
    for (const auto& n : list) {
      FaultEvent e = instance(n);
      if (!seen.insert(static_cast<int>(e.sensor)).second) {
        throw Bad(where(n) + ": sensor " + to_string(e.sensor) + " appears twice");
      }
      c.events.push_back(std::move(e));
    }
    *out = std::move(c);
    return true;
  } catch (const Bad& e) {
    *error = e.what();
  } catch (const YAML::Exception& e) {
    *error = std::string("unreadable content: ") + e.what();
  }
  return false;
}

std::string StateJournal::file_type(unsigned mode) {
  if (S_ISREG(mode)) return "a regular file";
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISLNK(mode)) return "a symbolic link";
  return "not a regular file";
}

StateJournal::LoadResult StateJournal::load(const std::string& path, std::uint32_t mmsi,
                                            Contents* out, std::string* error) {
  // O_NONBLOCK: opening a FIFO (or a device) must not wait for a writer; only a regular file
  // is read.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) {
    if (errno == ENOENT) return LoadResult::kMissing;
    *error = path + ": cannot open: " + std::strerror(errno);
    return LoadResult::kError;
  }
  struct stat sb {};
  if (::fstat(fd, &sb) != 0 || !S_ISREG(sb.st_mode)) {
    *error = path + ": " +
             (S_ISREG(sb.st_mode)
                  ? std::string("cannot stat: ") + std::strerror(errno)
                  : "is " + file_type(sb.st_mode) + ", not a state file (a regular file)");
    ::close(fd);
    return LoadResult::kError;
  }
  std::string text;
  char buf[8192];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0) {
      if (errno == EINTR) continue;
      *error = path + ": cannot read: " + std::strerror(errno);
      ::close(fd);
      return LoadResult::kError;
    }
    if (n == 0) break;
    text.append(buf, static_cast<std::size_t>(n));
    if (text.size() > (1u << 20)) {
      *error = path + ": larger than 1 MiB: not a state file";
      ::close(fd);
      return LoadResult::kError;
    }
  }
  ::close(fd);
  std::string why;
  if (!parse(text, mmsi, out, &why)) {
    *error = path + ": " + why;
    return LoadResult::kError;
  }
  return LoadResult::kLoaded;
}

bool StateJournal::write_atomic(const std::string& path, const std::string& text,
                                std::string* error) {
  const std::string tmp = path + ".tmp";
  const auto fail = [&](const std::string& what, int fd) {
    *error = what + ": " + std::strerror(errno);
    if (fd >= 0) ::close(fd);
    ::unlink(tmp.c_str());
    return false;
  };
  // A fresh file, never whatever is at <path>.tmp (a FIFO there would block the open).
  if (::unlink(tmp.c_str()) != 0 && errno != ENOENT) return fail("cannot remove " + tmp, -1);
  const int fd =
      ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK, 0640);
  if (fd < 0) return fail("cannot create " + tmp, -1);
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return fail("cannot write " + tmp, fd);
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) return fail("cannot fsync " + tmp, fd);
  if (::close(fd) != 0) return fail("cannot close " + tmp, -1);
  if (::rename(tmp.c_str(), path.c_str()) != 0)
    return fail("cannot rename " + tmp + " to " + path, -1);
  // The rename is durable once the directory is.
  std::string dir = std::filesystem::path(path).parent_path().string();
  if (dir.empty()) dir = ".";
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd < 0 || ::fsync(dfd) != 0) {
    *error = "cannot fsync directory " + dir + ": " + std::strerror(errno);
    if (dfd >= 0) ::close(dfd);
    return false;
  }
  ::close(dfd);
  return true;
}

std::string StateJournal::set_aside(const std::string& path, std::string* error) {
  const double now =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  const std::string to = path + ".corrupt-" + utc_stamp(now, "%Y%m%dT%H%M%SZ");
  if (::rename(path.c_str(), to.c_str()) != 0) {
    *error = "cannot rename " + path + " to " + to + ": " + std::strerror(errno);
    return "";
  }
  return to;
}

void StateJournal::seed(const FaultEvent& ev) {
  const int i = static_cast<int>(ev.sensor);
  if (i < 0 || i > 2) return;
  latest_[i] = ev;
  have_[i] = true;
}

bool StateJournal::record(const FaultEvent& ev) {
  seed(ev);
  return save();
}

bool StateJournal::save() {
  std::vector<FaultEvent> events;
  for (int i = 0; i < 3; ++i) {
    if (have_[i]) events.push_back(latest_[i]);
  }
  const double now =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  std::string error;
  const bool ok = write_atomic(path_, serialise(mmsi_, events, now), &error);
  std::lock_guard<std::mutex> lock(m_);
  error_ = ok ? "" : error;
  if (ok) ++saves_;
  return ok;
}

std::string StateJournal::last_error() const {
  std::lock_guard<std::mutex> lock(m_);
  return error_;
}

std::uint64_t StateJournal::saves() const {
  std::lock_guard<std::mutex> lock(m_);
  return saves_;
}

}  // namespace usvfdi::dds_service
