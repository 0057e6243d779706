#pragma once
// Writers of the analysis outputs (system.md, primitives.md "Outputs a session analysis writes").

#include "dreamsense/core/output_file.hpp"
#include "dreamsense/primitives/catalogue.hpp"
#include "dreamsense/sources/session.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <optional>
#include <vector>

namespace dreamsense::exporters {

// primitives.jsonl: one record per primitive per tick (primitive_json.hpp).
class PrimitivesJsonlWriter {
 public:
  Status open(const std::filesystem::path& path) { return file_.open(path); }
  Status write(const std::vector<primitives::PrimitiveRecord>& records);
  Status commit() { return file_.commit(); }

 private:
  OutputFile file_;
};

}  // namespace dreamsense::exporters
