#pragma once
// The primitive table, filled by the primitive families: each family source (body.cpp, face.cpp,
// audio.cpp, objects.cpp, ...) defines `register_<family>_primitives(PrimitiveRegistry&)`, which
// adds one row per primitive it answers, next to the functions that answer them. The evaluator
// holds no per-primitive code: it asks the rows. Adding a family = its source + one
// `ds_primitive_family(<family> ...)` line in primitives/CMakeLists.txt (docs/architecture.md,
// "Adding a primitive family"). A primitive without a row is always disabled.

#include "dreamsense/primitives/context.hpp"

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace dreamsense::primitives {

// One primitive: the blackboard keys it reads (every one must have a writer for it to be
// enabled) and how it is answered at each tick, with its default query (the family's options
// block, PrimitiveContext::family_options).
struct PrimitiveRow {
  PrimitiveId id = PrimitiveId::kCheckMutualGaze;
  std::vector<std::string> reads;
  std::function<PrimitiveRecord(const PrimitiveContext&)> evaluate;
};

class PrimitiveRegistry {
 public:
  // A second row for the same primitive, a row without keys or without a function are
  // programmer errors (CheckFailure).
  void add(PrimitiveRow row);
  // The row of `answer(ctx)`, a primitive function returning Answer<V>.
  template <typename F>
  void add(PrimitiveId id, std::vector<std::string> reads, F answer) {
    add(PrimitiveRow{id, std::move(reads), [id, answer](const PrimitiveContext& ctx) {
                       return to_record(id, ctx.tick(), answer(ctx));
                     }});
  }
  // Null when no family answers `id`.
  const PrimitiveRow* find(PrimitiveId id) const;

 private:
  std::array<std::optional<PrimitiveRow>, kPrimitiveCount> rows_;
};

// Every family built into the primitives library (generated from primitives/CMakeLists.txt).
const PrimitiveRegistry& builtin_primitives();

}  // namespace dreamsense::primitives
