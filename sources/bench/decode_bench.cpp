// What decoding a camera frame costs, and what is left to take from it (docs/session_format.md,
// "What is left to take from decoding"). Frames of a real session's colour stream:
//   DREAMSENSE_DEMO_SESSION=DIR build/bin/decode_bench
// (DIR from `dreamsense demo --out DIR --no-analyze`; stream camera_middle unless
// DREAMSENSE_DECODE_STREAM names another mjpeg stream). BM_ReaderDecode is the reader's own path
// (SessionReader::decode_record); BM_LibjpegDecode calls libjpeg-turbo the same way with one
// setting changed per mode, to see which part of a decode each would save.

#include "dreamsense/sources/session.hpp"

#include <benchmark/benchmark.h>

#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <jpeglib.h>
#include <string>
#include <vector>

namespace dreamsense::sources {
namespace {

constexpr size_t kFrames = 5;  // spread over the stream

struct Frames {
  std::unique_ptr<SessionReader> reader;
  SensorId stream;
  std::vector<size_t> records;             // indices into reader->records(stream)
  std::vector<std::vector<JOCTET>> bytes;  // the same frames' JPEG bytes
  std::string problem;                     // why there are none
};

const Frames& frames() {
  static const Frames f = [] {
    Frames out;
    const char* dir = std::getenv("DREAMSENSE_DEMO_SESSION");
    if (dir == nullptr) {
      out.problem = "set DREAMSENSE_DEMO_SESSION to a session folder (dreamsense demo --out DIR)";
      return out;
    }
    const char* stream = std::getenv("DREAMSENSE_DECODE_STREAM");
    out.stream = stream != nullptr ? stream : "camera_middle";
    SessionReaderOptions o;
    o.only = {out.stream};
    o.decode_threads = 0;
    auto r = SessionReader::open(dir, o);
    if (!r) {
      out.problem = r.error().message;
      return out;
    }
    const std::vector<RecordLocation> all = (*r)->records(out.stream);
    const StreamEntry* entry = (*r)->manifest().find(out.stream);
    if (all.size() < kFrames || entry == nullptr || entry->encoding != "mjpeg") {
      out.problem = out.stream + ": not an mjpeg stream with at least 5 frames";
      return out;
    }
    std::ifstream data(std::string(dir) + "/" + entry->file, std::ios::binary);
    for (size_t i = 0; i < kFrames; ++i) {
      const size_t k = (2 * i + 1) * all.size() / (2 * kFrames);
      out.records.push_back(k);
      std::vector<JOCTET> b(all[k].size);
      data.seekg(static_cast<std::streamoff>(all[k].offset));
      data.read(reinterpret_cast<char*>(b.data()), static_cast<std::streamsize>(b.size()));
      out.bytes.push_back(std::move(b));
    }
    out.reader = std::move(*r);
    return out;
  }();
  return f;
}

void BM_ReaderDecode(benchmark::State& state) {
  const Frames& f = frames();
  if (!f.problem.empty()) {
    state.SkipWithError(f.problem.c_str());
    return;
  }
  size_t i = 0;
  for (auto _ : state) {
    auto frame = f.reader->decode_record(f.stream, f.records[i++ % kFrames]);
    if (!frame) {
      state.SkipWithError(frame.error().message.c_str());
      return;
    }
    benchmark::DoNotOptimize(frame);
  }
}
BENCHMARK(BM_ReaderDecode)->Unit(benchmark::kMillisecond);

enum Mode { kBgr, kGrey, kHalf, kEighth, kFastDct };

// Decodes one frame into `rows` (resized to the output). libjpeg's default error handler ends
// the program on a frame it cannot decode: run it on a session `dreamsense check` passes.
void decode(const std::vector<JOCTET>& bytes, Mode mode, std::vector<JSAMPLE>& rows) {
  jpeg_decompress_struct cinfo;
  jpeg_error_mgr err;
  cinfo.err = jpeg_std_error(&err);
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, bytes.data(), static_cast<unsigned long>(bytes.size()));
  jpeg_read_header(&cinfo, TRUE);
  cinfo.out_color_space = mode == kGrey ? JCS_GRAYSCALE : JCS_EXT_BGR;
  cinfo.scale_denom = mode == kHalf ? 2 : mode == kEighth ? 8 : 1;
  if (mode == kFastDct) cinfo.dct_method = JDCT_IFAST;
  jpeg_start_decompress(&cinfo);
  const size_t stride = static_cast<size_t>(cinfo.output_width) * cinfo.output_components;
  rows.resize(stride * cinfo.output_height);
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW row = rows.data() + stride * cinfo.output_scanline;
    jpeg_read_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
}

void BM_LibjpegDecode(benchmark::State& state) {
  const Frames& f = frames();
  if (!f.problem.empty()) {
    state.SkipWithError(f.problem.c_str());
    return;
  }
  const auto mode = static_cast<Mode>(state.range(0));
  std::vector<JSAMPLE> rows;
  size_t i = 0;
  for (auto _ : state) {
    decode(f.bytes[i++ % kFrames], mode, rows);
    benchmark::DoNotOptimize(rows.data());
  }
  static const char* const kNames[] = {"bgr", "grey", "half_scale", "eighth_scale", "ifast_dct"};
  state.SetLabel(kNames[mode]);
}
BENCHMARK(BM_LibjpegDecode)
    ->Arg(kBgr)
    ->Arg(kGrey)
    ->Arg(kHalf)
    ->Arg(kEighth)
    ->Arg(kFastDct)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dreamsense::sources

BENCHMARK_MAIN();
