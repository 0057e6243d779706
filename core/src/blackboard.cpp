#include "dreamsense/core/blackboard.hpp"

#include <fmt/format.h>

namespace dreamsense {

const detail::Slot* BlackboardView::find(std::string_view name, std::type_index type) const {
  auto it = state_->slots.find(name);
  if (it == state_->slots.end()) return nullptr;
  if (it->second->type != type)
    throw CheckFailure(fmt::format("blackboard key '{}' read as {} but holds {}", name, type.name(),
                                   it->second->type.name()));
  return it->second.get();
}

void BlackboardWriter::put(const char* key, std::type_index type, std::shared_ptr<const void> value,
                           Timestamp stamp, float confidence) {
  DS_CHECK(key != nullptr);
  DS_CHECK(stamp.is_set());
  writes_.push_back(Write{key, type, detail::Record{std::move(value), stamp, confidence, source_}});
}

Status BlackboardOptions::check() const {
  if (history_length < 1)
    return make_error(ErrorCode::kInvalidArgument,
                      "BlackboardOptions: history_length must be >= 1");
  return ok_status();
}

Blackboard::Blackboard(BlackboardOptions options)
    : options_(options), state_(std::make_shared<detail::State>()) {}

BlackboardView Blackboard::snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return BlackboardView(state_);
}

void Blackboard::apply(detail::State& next, BlackboardWriter& writer) const {
  for (auto& w : writer.writes_) {
    auto it = next.slots.find(w.key);
    auto slot = std::make_shared<detail::Slot>();
    if (it != next.slots.end()) {
      if (it->second->type != w.type)
        throw CheckFailure(fmt::format("blackboard key '{}' written as {} but holds {}", w.key,
                                       w.type.name(), it->second->type.name()));
      *slot = *it->second;  // copies the (short) history; values are shared, not copied
    }
    slot->type = w.type;
    slot->history.push_front(std::move(w.record));
    while (slot->history.size() > options_.history_length) slot->history.pop_back();
    next.slots[w.key] = std::move(slot);
  }
  writer.writes_.clear();
}

void Blackboard::commit(BlackboardWriter& writer, Timestamp tick) {
  std::vector<BlackboardWriter> one;
  one.push_back(std::move(writer));
  commit(one, tick);
  writer = std::move(one.front());
}

void Blackboard::commit(std::vector<BlackboardWriter>& writers, Timestamp tick) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto next = std::make_shared<detail::State>(*state_);  // copies the key -> slot pointers only
  for (auto& w : writers) apply(*next, w);
  next->stamp = tick;
  next->version = state_->version + 1;
  state_ = std::move(next);
}

void Blackboard::clear() {
  std::lock_guard<std::mutex> lock(mutex_);
  state_ = std::make_shared<detail::State>();
}

}  // namespace dreamsense
