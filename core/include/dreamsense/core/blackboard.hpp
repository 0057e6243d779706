#pragma once
// The blackboard (D4.2's "global buffer"): typed entries, each with stamp, confidence and the
// analyser that wrote it, plus a short history per entry for temporal primitives.
//
// Writers collect their writes in a BlackboardWriter (scoped to one analyser, so provenance is
// automatic); Blackboard::commit publishes them atomically. Readers take a BlackboardView: an
// immutable snapshot, so a primitive never sees a half-updated tick.
// An entry whose value is null records "the analyser ran at `stamp` and found nothing", which lets
// primitives tell no_data from stale.

#include "dreamsense/core/status.hpp"
#include "dreamsense/core/timestamp.hpp"

#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <typeindex>
#include <vector>

namespace dreamsense {

// A typed blackboard key; declare as `inline constexpr Key<T> kName{"module.name"};`.
template <typename T>
struct Key {
  const char* name;
};

template <typename T>
struct Entry {
  std::shared_ptr<const T> value;  // null: observed nothing at `stamp`
  Timestamp stamp;
  float confidence = 0.f;
  std::string source;
  bool present() const { return value != nullptr; }
};

namespace detail {
struct Record {
  std::shared_ptr<const void> value;
  Timestamp stamp;
  float confidence = 0.f;
  std::string source;
};
struct Slot {
  std::type_index type = typeid(void);
  std::deque<Record> history;  // newest first
};
struct State {
  Timestamp stamp = Timestamp::unset();
  uint64_t version = 0;
  std::map<std::string, std::shared_ptr<const Slot>, std::less<>> slots;
};
}  // namespace detail

class BlackboardView {
 public:
  BlackboardView() : state_(std::make_shared<detail::State>()) {}
  explicit BlackboardView(std::shared_ptr<const detail::State> s) : state_(std::move(s)) {}

  // The newest entry, or nullopt if the key was never written.
  template <typename T>
  std::optional<Entry<T>> get(Key<T> key) const {
    const detail::Slot* slot = find(key.name, typeid(T));
    if (slot == nullptr || slot->history.empty()) return std::nullopt;
    return to_entry<T>(slot->history.front());
  }
  // Up to `n` newest entries, newest first.
  template <typename T>
  std::vector<Entry<T>> history(Key<T> key, size_t n = SIZE_MAX) const {
    std::vector<Entry<T>> out;
    const detail::Slot* slot = find(key.name, typeid(T));
    if (slot == nullptr) return out;
    for (const auto& r : slot->history) {
      if (out.size() >= n) break;
      out.push_back(to_entry<T>(r));
    }
    return out;
  }
  bool contains(std::string_view key) const { return state_->slots.count(key) > 0; }
  Timestamp stamp() const { return state_->stamp; }  // tick of the last commit
  uint64_t version() const { return state_->version; }

 private:
  const detail::Slot* find(std::string_view name, std::type_index type) const;
  template <typename T>
  static Entry<T> to_entry(const detail::Record& r) {
    return Entry<T>{std::static_pointer_cast<const T>(r.value), r.stamp, r.confidence, r.source};
  }
  std::shared_ptr<const detail::State> state_;
};

class BlackboardWriter {
 public:
  explicit BlackboardWriter(std::string source) : source_(std::move(source)) {}

  template <typename T>
  void set(Key<T> key, T value, Timestamp stamp, float confidence) {
    put(key.name, typeid(T), std::make_shared<const T>(std::move(value)), stamp, confidence);
  }
  // Records that the analyser looked at `stamp` and found nothing.
  template <typename T>
  void set_absent(Key<T> key, Timestamp stamp) {
    put(key.name, typeid(T), nullptr, stamp, 0.f);
  }
  const std::string& source() const { return source_; }
  bool empty() const { return writes_.empty(); }
  size_t size() const { return writes_.size(); }
  // The keys written so far, in write order (a key written twice appears twice).
  std::vector<std::string> keys() const {
    std::vector<std::string> out;
    for (const auto& w : writes_) out.push_back(w.key);
    return out;
  }

 private:
  friend class Blackboard;
  struct Write {
    std::string key;
    std::type_index type;
    detail::Record record;
  };
  void put(const char* key, std::type_index type, std::shared_ptr<const void> value,
           Timestamp stamp, float confidence);
  std::string source_;
  std::vector<Write> writes_;
};

struct BlackboardOptions {
  size_t history_length = 64;  // per entry; 64 ticks = 2.56 s at 25 Hz
  Status check() const;
};

class Blackboard {
 public:
  explicit Blackboard(BlackboardOptions options = {});

  BlackboardView snapshot() const;
  // Publishes all writes at once and moves the snapshot stamp to `tick`. Writing a key with a
  // different type than before is a programmer error (CheckFailure).
  void commit(BlackboardWriter& writer, Timestamp tick);
  void commit(std::vector<BlackboardWriter>& writers, Timestamp tick);
  void clear();

 private:
  void apply(detail::State& next, BlackboardWriter& writer) const;
  BlackboardOptions options_;
  mutable std::mutex mutex_;
  std::shared_ptr<const detail::State> state_;
};

}  // namespace dreamsense
