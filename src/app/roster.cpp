#include "roster.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "usv_fdi/core/text.hpp"

namespace usvfdi::app {

bool parse_roster(const std::string& text, const std::string& name, std::set<std::uint32_t>* out,
                  std::string* why) {
  std::istringstream in(text);
  std::string line;
  int number = 0;
  std::set<std::uint32_t> got;
  while (std::getline(in, line)) {
    ++number;
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos) continue;
    const std::size_t last = line.find_last_not_of(" \t\r");
    const std::string word = line.substr(first, last - first + 1);
    bool ok = word.size() <= 9 && word.find_first_not_of("0123456789") == std::string::npos;
    const unsigned long v = ok ? std::strtoul(word.c_str(), nullptr, 10) : 0;
    ok = ok && v >= 1 && v <= 999999999;
    if (!ok) {
      *why = name + ":" + std::to_string(number) + ": '" + escape_text(word) +
             "' is not an MMSI (one MMSI 1..999999999 per line, '#' starts a comment)";
      return false;
    }
    got.insert(static_cast<std::uint32_t>(v));
  }
  if (got.empty()) {
    *why = name + ": no MMSI in the roster";
    return false;
  }
  *out = std::move(got);
  return true;
}

bool load_roster(const std::string& path, std::set<std::uint32_t>* out, std::string* why) {
  std::ifstream f(path, std::ios::binary);
  if (!f) {
    *why = "cannot read the roster " + path + ": " + std::strerror(errno);
    return false;
  }
  std::ostringstream os;
  os << f.rdbuf();
  return parse_roster(os.str(), path, out, why);
}

const char* to_string(RosterState s) {
  switch (s) {
    case RosterState::kHeard:
      return "heard";
    case RosterState::kSilent:
      return "silent";
    case RosterState::kNeverHeard:
      return "never_heard";
    case RosterState::kNotOnRoster:
      return "not_on_roster";
    case RosterState::kNoRoster:
      break;
  }
  return "no_roster";
}

RosterState RosterWatch::state(std::uint32_t mmsi, const VesselLiveness& live) const {
  if (!active()) return RosterState::kNoRoster;
  const bool heard = !std::isnan(live.age(mmsi, 0.0));
  if (!on_roster(mmsi)) return RosterState::kNotOnRoster;
  if (!heard) return RosterState::kNeverHeard;
  return live.silent(mmsi) ? RosterState::kSilent : RosterState::kHeard;
}

std::vector<std::uint32_t> RosterWatch::never_heard(const VesselLiveness& live) const {
  std::vector<std::uint32_t> out;
  for (const std::uint32_t m : roster_) {
    if (std::isnan(live.age(m, 0.0))) out.push_back(m);
  }
  return out;
}

std::vector<std::uint32_t> RosterWatch::shown(const VesselLiveness& live) const {
  std::set<std::uint32_t> all(roster_);
  for (const std::uint32_t m : live.vessels()) all.insert(m);
  return {all.begin(), all.end()};
}

std::vector<RosterWatch::Change> RosterWatch::evaluate(const VesselLiveness& live, double now) {
  std::vector<Change> out;
  if (!active()) return out;
  for (const std::uint32_t m : roster_) {
    const bool heard = !std::isnan(live.age(m, now));
    if (!heard && now - start_ >= grace_ && reported_missing_.insert(m).second) {
      out.push_back(Change{m, RosterState::kNeverHeard, now - start_});
    } else if (heard && reported_missing_.erase(m) > 0) {
      out.push_back(Change{m, RosterState::kHeard, now - start_});
    }
  }
  for (const std::uint32_t m : live.vessels()) {
    if (!on_roster(m) && reported_foreign_.insert(m).second) {
      out.push_back(Change{m, RosterState::kNotOnRoster, now - start_});
    }
  }
  return out;
}

}  // namespace usvfdi::app
