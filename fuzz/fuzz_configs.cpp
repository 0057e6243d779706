// Configuration files: pipeline.yaml (runner/pipeline_config.hpp) and the recording / live
// device configuration (sources/recorder.hpp). Input: byte 0 picks the reader.
#include "dreamsense/runner/pipeline_config.hpp"
#include "dreamsense/sources/recorder.hpp"

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dreamsense;
  if (size < 1) return 0;
  const std::string_view file = fuzz::as_text(data + 1, size - 1);
  const auto& scratch = fuzz::scratch();
  if (data[0] % 2 == 0) {
    auto c = runner::PipelineConfig::read(scratch.write("pipeline.yaml", file));
    if (c)
      for (const auto& [name, analyzer] : c->analyzers) (void)c->where(name);
  } else {
    auto c = sources::read_record_config(scratch.write("rec.yaml", file));
    if (c) (void)c->check();
  }
  return 0;
}
