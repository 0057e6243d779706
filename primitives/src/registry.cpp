#include "dreamsense/primitives/registry.hpp"

namespace dreamsense::primitives {

void PrimitiveRegistry::add(PrimitiveRow row) {
  const int n = static_cast<int>(row.id);
  DS_CHECK(n >= 1 && n <= kPrimitiveCount);
  DS_CHECK(!row.reads.empty());
  DS_CHECK(static_cast<bool>(row.evaluate));
  auto& slot = rows_[static_cast<size_t>(n - 1)];
  if (slot)
    throw CheckFailure(
        fmt::format("primitive {} {} is registered twice", info(row.id).code, info(row.id).name));
  slot = std::move(row);
}

const PrimitiveRow* PrimitiveRegistry::find(PrimitiveId id) const {
  const int n = static_cast<int>(id);
  if (n < 1 || n > kPrimitiveCount) return nullptr;
  const auto& slot = rows_[static_cast<size_t>(n - 1)];
  return slot ? &*slot : nullptr;
}

}  // namespace dreamsense::primitives
