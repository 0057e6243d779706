#include "dreamsense/export/primitive_json.hpp"
#include "dreamsense/export/writers.hpp"

namespace dreamsense::exporters {

Status PrimitivesJsonlWriter::write(const std::vector<primitives::PrimitiveRecord>& records) {
  std::string text;
  for (const auto& r : records) {
    text += to_json(r).dump();
    text += '\n';
  }
  return file_.write(text);
}

}  // namespace dreamsense::exporters
