#pragma once
// The JSON form of a primitive record (a line of primitives.jsonl, ../shared/spec/primitives.md):
//   {"stamp_ns", "primitive", "id", "status", "confidence", "value", "legacy", "source",
//    "data_stamp_ns" (when known), "query" (parametrised primitives)}
// One adapter both ways: `to_json` writes the typed record (with DREAM's legacy vector from
// dream/), `record_from_json` reads it back into the typed record (evaluations, tools).

#include "dreamsense/core/status.hpp"
#include "dreamsense/primitives/catalogue.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <vector>

namespace dreamsense::exporters {

nlohmann::json to_json(const primitives::PrimitiveRecord& record);
nlohmann::json value_json(const primitives::PrimitiveRecord& record);  // the "value" member
nlohmann::json query_json(const primitives::PrimitiveQuery& query);    // null for monostate

// A record from its JSON form; a record that does not follow the format is an error saying
// which member is wrong.
Result<primitives::PrimitiveRecord> record_from_json(const nlohmann::json& j);

// Every record of a primitives.jsonl file, in file order; a line that is not a record is an
// error naming the file and line.
Result<std::vector<primitives::PrimitiveRecord>> read_primitives_jsonl(
    const std::filesystem::path& path);

}  // namespace dreamsense::exporters
