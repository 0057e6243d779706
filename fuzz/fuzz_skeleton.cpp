// Skeleton files: a session's skeleton stream (JSON lines, sources/session.hpp) and the skeleton
// text files of the action datasets (UTKinect joints, MSR Action3D; eval/action_datasets.hpp).
// Input: byte 0 picks the reader, the rest is the file.
#include "dreamsense/eval/action_datasets.hpp"
#include "dreamsense/sources/session.hpp"

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace dreamsense;
  if (size < 1) return 0;
  const std::string_view file = fuzz::as_text(data + 1, size - 1);
  const auto& scratch = fuzz::scratch();
  switch (data[0] % 3) {
    case 0: {
      scratch.write("session/session.yaml",
                    "format: dreamsense-session\nformat_version: 1\nname: fuzz\ncomplete: true\n"
                    "streams:\n  - {id: front.skeleton, kind: skeleton, encoding: jsonl, "
                    "file: s.jsonl, rate_hz: 30}\n");
      scratch.write("session/s.jsonl", file);
      sources::SessionReaderOptions options;
      options.decode_threads = 0;
      options.allow_damaged = true;
      auto reader = sources::SessionReader::open(scratch.path() / "session", options);
      if (!reader) return 0;
      for (int frames = 0; frames < 1000; ++frames)
        if (!(*reader)->next()) break;
      (void)(*reader)->damage();
      break;
    }
    case 1:
      (void)eval::actions::read_utkinect_joints(scratch.write("joints_s01_e01.txt", file));
      break;
    default:
      (void)eval::actions::read_msr_skeleton(scratch.write("a01_s01_e01_skeleton.txt", file));
      break;
  }
  return 0;
}
