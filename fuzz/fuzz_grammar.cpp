// Speech grammars (modalities/speech): SRGS XML (parsed by our SRGS reader, then converted to
// JSGF) and JSGF (compiled by sphinxbase, then our garbage loop is added to its FSG text, as
// PsDecoder::create does before it loads a model). Input: byte 0 picks the format.
#include "dreamsense/speech/srgs.hpp"

#include "../modalities/speech/src/ps_backend.hpp"
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dreamsense;
  if (size < 1) return 0;
  const std::string text(fuzz::as_text(data + 1, size - 1));
  (void)fuzz::scratch();  // quiet logging
  if (data[0] % 2 == 0) {
    auto g = speech::SrgsGrammar::parse(text, "fuzz.grxml");
    if (g) (void)g->to_jsgf();
  } else {
    (void)speech::detail::compile_jsgf(text, "fuzz.gram", {"AA", "B", "SIL"});
  }
  return 0;
}
