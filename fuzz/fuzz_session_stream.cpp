// The indexed streams of a session (sources/session.hpp): colour "mjpeg", depth "raw16" and
// "png16": their index lines and data files, read frame by frame under the damage policy.
// Input: byte 0 picks the encoding; then the index file up to the first empty line ("\n\n"),
// then the data file.
#include "dreamsense/sources/session.hpp"

#include <fmt/format.h>

#include <array>

#include "fuzz_support.hpp"

namespace {

struct Encoding {
  const char* kind;
  const char* encoding;
};
constexpr std::array<Encoding, 3> kEncodings{
    {{"color", "mjpeg"}, {"depth", "raw16"}, {"depth", "png16"}}};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dreamsense;
  if (size < 1) return 0;
  const Encoding e = kEncodings[data[0] % kEncodings.size()];
  const std::string_view rest = fuzz::as_text(data + 1, size - 1);
  const size_t split = rest.find("\n\n");
  const std::string_view index = rest.substr(0, split);
  const std::string_view payload =
      split == std::string_view::npos ? std::string_view() : rest.substr(split + 2);
  const auto& scratch = fuzz::scratch();
  // 8 x 6 frames keep raw16 frames small (96 bytes) so that the fuzzer can make whole ones.
  scratch.write("session/session.yaml",
                fmt::format("format: dreamsense-session\nformat_version: 1\nname: fuzz\n"
                            "complete: true\nstreams:\n"
                            "  - {{id: s, kind: {}, encoding: {}, file: s.data, index: s.idx, "
                            "rate_hz: 25, width: 8, height: 6}}\n",
                            e.kind, e.encoding));
  scratch.write("session/s.idx", index);
  scratch.write("session/s.data", payload);
  sources::SessionReaderOptions options;
  options.decode_threads = 0;  // one thread: reproducible, and the fuzzer sees every branch
  options.allow_damaged = true;
  auto reader = sources::SessionReader::open(scratch.path() / "session", options);
  if (!reader) return 0;
  for (int frames = 0; frames < 1000; ++frames) {
    auto f = (*reader)->next();
    if (!f) break;
  }
  (void)(*reader)->damage();
  return 0;
}
