// session.yaml (sources/session.hpp): the manifest, its checks and the stream roles; then
// SessionReader::open on it (the stream files are absent: a clean error, never a crash).
#include "dreamsense/sources/session.hpp"

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dreamsense;
  const auto& scratch = fuzz::scratch();
  scratch.write("session/session.yaml", fuzz::as_text(data, size));
  const auto dir = scratch.path() / "session";
  auto manifest = sources::read_manifest(dir);
  if (manifest) {
    (void)sources::stream_roles(*manifest);
    (void)sources::check_manifest(*manifest);
    sources::SessionReaderOptions options;
    options.decode_threads = 0;
    (void)sources::SessionReader::open(dir, options);
  }
  return 0;
}
