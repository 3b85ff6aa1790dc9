// Who may update an instance the monitor (or a dashboard) shows: the writer that owns it.
//
// A sample of a keyed instance (a vessel's fault instance, a vessel's status) is shown only if it
// comes from the instance's owner: the first writer seen for it, or — under DDS Security — the
// writer whose authenticated identity is confined to that vessel (its only partition is the
// vessel's, which access control checked against its signed permissions). The owner's sequence
// never goes backwards. Another writer of the same instance is a conflict: its samples are held
// (the latest per writer) and not shown, and the conflict is reported once per writer. When the
// owner leaves (its writer is no longer matched), the held writer with the highest sequence takes
// over: a sidecar that restarted with a new writer comes back that way. Pure logic, no DDS: writers
// are named by an opaque id (the GUID text).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace usvfdi::app {

struct WriterRef {
  std::string id;  ///< unique per writer (its GUID)
  std::uint32_t vessel =
      0;  ///< the vessel its authenticated identity is confined to; 0: none known
  bool operator==(const WriterRef& o) const { return id == o.id; }
};

/// What offer() did with a sample and why.
struct OwnerDecision {
  enum class Verdict { kShown, kHeld, kRefused };
  enum class Why {
    kOwner,          ///< from the owner (or the first writer): shown
    kTakeover,       ///< an authenticated writer of the vessel displaced an unauthenticated owner
    kOwnerGone,      ///< the previous owner had left: this writer took over
    kSecondWriter,   ///< another writer of an owned instance: held, not shown (a conflict)
    kBackwards,      ///< the owner's sequence went backwards: refused
    kForeignVessel,  ///< the writer is confined to another vessel: refused
  };
  Verdict verdict = Verdict::kShown;
  Why why = Why::kOwner;
  WriterRef owner;  ///< the owner before the decision (empty id: none)
  std::uint64_t owner_sequence = 0;
  bool report = false;  ///< true: a conflict or a change of owner to report (once per writer)
};

inline const char* to_string(OwnerDecision::Why w) {
  switch (w) {
    case OwnerDecision::Why::kOwner:
      return "owner";
    case OwnerDecision::Why::kTakeover:
      return "authenticated writer took over";
    case OwnerDecision::Why::kOwnerGone:
      return "previous owner gone";
    case OwnerDecision::Why::kSecondWriter:
      return "second writer";
    case OwnerDecision::Why::kBackwards:
      return "sequence backwards";
    case OwnerDecision::Why::kForeignVessel:
      return "writer confined to another vessel";
  }
  return "?";
}

template <class Key, class Sample>
class InstanceOwners {
 public:
  /// Offers `sample` (sequence `seq`) of instance `key` of vessel `vessel` from writer `w`.
  OwnerDecision offer(const Key& key, std::uint32_t vessel, const WriterRef& w, std::uint64_t seq,
                      const Sample& sample) {
    OwnerDecision d;
    auto it = slots_.find(key);
    if (it != slots_.end()) {
      d.owner = it->second.owner;
      d.owner_sequence = it->second.seq;
    }
    if (w.vessel != 0 && w.vessel != vessel) {
      d.verdict = OwnerDecision::Verdict::kRefused;
      d.why = OwnerDecision::Why::kForeignVessel;
      Slot& s = slots_.try_emplace(key).first->second;  // new: empty (nothing shown)
      d.report = s.reported.insert_or_assign(w.id, true).second;
      return d;
    }
    if (it == slots_.end() || it->second.empty) {
      Slot& s = slots_[key];
      s.empty = false;
      s.owner = w;
      s.seq = seq;
      s.sample = sample;
      return d;
    }
    Slot& s = it->second;
    if (s.owner.id == w.id) {
      if (seq < s.seq) {
        d.verdict = OwnerDecision::Verdict::kRefused;
        d.why = OwnerDecision::Why::kBackwards;
        d.report = true;
        return d;
      }
      s.owner = w;
      s.seq = seq;
      s.sample = sample;
      s.gone = false;
      return d;
    }
    const bool authenticated = w.vessel == vessel;
    if ((authenticated && s.owner.vessel != vessel) || s.gone) {
      d.why = s.gone ? OwnerDecision::Why::kOwnerGone : OwnerDecision::Why::kTakeover;
      d.report = true;
      s.held.erase(w.id);
      s.owner = w;
      s.seq = seq;
      s.sample = sample;
      s.gone = false;
      return d;
    }
    d.verdict = OwnerDecision::Verdict::kHeld;
    d.why = OwnerDecision::Why::kSecondWriter;
    d.report = s.reported.insert_or_assign(w.id, true).second;
    s.held[w.id] = Held{w, seq, sample};
    return d;
  }

  /// The sample shown for `key` (nullptr: none) and its owner.
  const Sample* shown(const Key& key) const {
    const auto it = slots_.find(key);
    return it == slots_.end() || it->second.empty ? nullptr : &it->second.sample;
  }
  Sample* shown(const Key& key) {
    const auto it = slots_.find(key);
    return it == slots_.end() || it->second.empty ? nullptr : &it->second.sample;
  }
  const WriterRef* owner(const Key& key) const {
    const auto it = slots_.find(key);
    return it == slots_.end() || it->second.empty ? nullptr : &it->second.owner;
  }

  /// Writer `id` left. Its held samples are dropped; every instance it owned is marked gone and,
  /// if another writer's sample is held for it, the one with the highest sequence takes over.
  /// Returns the instances whose owner was `id` (each with the new owner, or nullopt if none).
  std::vector<std::pair<Key, std::optional<WriterRef>>> writer_gone(const std::string& id) {
    std::vector<std::pair<Key, std::optional<WriterRef>>> out;
    for (auto& [key, s] : slots_) {
      s.held.erase(id);
      if (s.empty || s.owner.id != id) continue;
      s.gone = true;
      std::optional<WriterRef> next;
      auto best = s.held.end();
      for (auto h = s.held.begin(); h != s.held.end(); ++h) {
        if (best == s.held.end() || h->second.seq > best->second.seq) best = h;
      }
      if (best != s.held.end()) {
        s.owner = best->second.writer;
        s.seq = best->second.seq;
        s.sample = best->second.sample;
        s.gone = false;
        next = s.owner;
        s.held.erase(best);
      }
      out.emplace_back(key, next);
    }
    return out;
  }
  /// Writer `id` is matched again (same writer, e.g. after a network partition healed).
  void writer_back(const std::string& id) {
    for (auto& [key, s] : slots_) {
      if (!s.empty && s.owner.id == id) s.gone = false;
    }
  }

  /// Every instance shown, in key order.
  template <class F>
  void for_each(F f) const {
    for (const auto& [key, s] : slots_) {
      if (!s.empty) f(key, s.sample);
    }
  }
  template <class F>
  void for_each(F f) {
    for (auto& [key, s] : slots_) {
      if (!s.empty) f(key, s.sample);
    }
  }
  std::size_t size() const {
    std::size_t n = 0;
    for (const auto& kv : slots_) n += kv.second.empty ? 0 : 1;
    return n;
  }

 private:
  struct Held {
    WriterRef writer;
    std::uint64_t seq = 0;
    Sample sample;
  };
  struct Slot {
    bool empty = true;  ///< nothing shown yet (only refusals recorded)
    WriterRef owner;
    std::uint64_t seq = 0;
    Sample sample{};
    bool gone = false;                     ///< the owner's writer is no longer matched
    std::map<std::string, Held> held;      ///< latest sample of each other writer
    std::map<std::string, bool> reported;  ///< writers whose conflict was reported
  };
  std::map<Key, Slot> slots_;
};

}  // namespace usvfdi::app
