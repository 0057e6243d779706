#include "dreamsense/voice_id/voice_model.hpp"

#include "dreamsense/audio/noise_suppressor.hpp"
#include "dreamsense/core/file_storage_check.hpp"
#include "dreamsense/core/opencv_error.hpp"

#include <opencv2/core/persistence.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <system_error>

namespace dreamsense::voice_id {
namespace fs = std::filesystem;

Status VoiceTrainOptions::check() const {
  if (auto s = features.check(); !s) return s;
  if (auto s = ubm.check(); !s) return s;
  if (auto s = map.check(); !s) return s;
  if (!std::isfinite(threshold))
    return make_error(ErrorCode::kInvalidArgument, "VoiceTrainOptions: threshold must be finite");
  if (!(score_scale > 0))
    return make_error(ErrorCode::kInvalidArgument, "VoiceTrainOptions: score_scale must be > 0");
  return ok_status();
}

Status VoiceModel::check() const {
  if (auto s = features.check(); !s) return s;
  if (ubm.components() == 0)
    return make_error(ErrorCode::kInvalidArgument, "voice model: no background model");
  if (ubm.dimension() != features.dimension())
    return make_error(ErrorCode::kInvalidArgument,
                      "voice model: background model has dimension {}, features {}",
                      ubm.dimension(), features.dimension());
  if (speakers.empty())
    return make_error(ErrorCode::kInvalidArgument, "voice model: no enrolled speaker");
  if (!cmn_prior.empty() &&
      (cmn_prior.rows != 1 || cmn_prior.cols != ubm.dimension() || cmn_prior.type() != CV_64F))
    return make_error(ErrorCode::kInvalidArgument, "voice model: cmn_prior must be 1 x {}",
                      ubm.dimension());
  std::map<std::string, int> seen;
  for (const auto& s : speakers) {
    if (s.id.empty() || s.id == kUnknownSpeaker)
      return make_error(ErrorCode::kInvalidArgument, "voice model: invalid speaker id '{}'", s.id);
    if (seen[s.id]++)
      return make_error(ErrorCode::kInvalidArgument, "voice model: speaker '{}' enrolled twice",
                        s.id);
    if (s.model.components() != ubm.components() || s.model.dimension() != ubm.dimension())
      return make_error(ErrorCode::kInvalidArgument,
                        "voice model: speaker '{}' has {} Gaussians of dimension {}, the "
                        "background model {} of {}",
                        s.id, s.model.components(), s.model.dimension(), ubm.components(),
                        ubm.dimension());
  }
  if (!std::isfinite(threshold) || !(score_scale > 0))
    return make_error(ErrorCode::kInvalidArgument,
                      "voice model: threshold must be finite and score_scale > 0");
  return ok_status();
}

Status VoiceModel::save(const fs::path& path) const {
  if (auto s = check(); !s) return s;
  const fs::path tmp = path.string() + ".part";
  try {
    cv::FileStorage f(tmp.string(), cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
    if (!f.isOpened()) return make_error(ErrorCode::kIoError, "{}: cannot write", path.string());
    f << "format" << kFormatName << "version" << kFormatVersion;
    f << "features"
      << "{";
    f << "frame_s" << features.frame_s << "hop_s" << features.hop_s << "preemphasis"
      << features.preemphasis << "filters" << features.filters << "cepstra" << features.cepstra
      << "low_hz" << features.low_hz << "high_hz" << features.high_hz << "delta_window"
      << features.delta_window << "delta_deltas" << static_cast<int>(features.delta_deltas)
      << "static_energy" << static_cast<int>(features.static_energy) << "drop_below_peak_db"
      << features.drop_below_peak_db << "above_floor_db" << features.above_floor_db
      << "min_level_db" << features.min_level_db << "mean_normalise"
      << static_cast<int>(features.mean_normalise) << "variance_normalise"
      << static_cast<int>(features.variance_normalise) << "noise_suppression"
      << static_cast<int>(features.noise_suppression) << "cmn_prior_frames"
      << features.cmn_prior_frames;
    f << "}";
    if (!cmn_prior.empty()) f << "cmn_prior" << cmn_prior;
    f << "map"
      << "{"
      << "relevance" << map.relevance << "adapt_weights" << static_cast<int>(map.adapt_weights)
      << "adapt_variances" << static_cast<int>(map.adapt_variances) << "variance_floor"
      << map.variance_floor << "}";
    f << "threshold" << threshold << "score_scale" << score_scale << "background" << background;
    f << "ubm"
      << "{"
      << "weights" << ubm.weights() << "means" << ubm.means() << "variances" << ubm.variances()
      << "}";
    f << "speakers"
      << "[";
    for (const auto& s : speakers)
      f << "{"
        << "id" << s.id << "name" << s.name << "utterances" << s.utterances << "frames" << s.frames
        << "weights" << s.model.weights() << "means" << s.model.means() << "variances"
        << s.model.variances() << "}";
    f << "]";
    f.release();
  } catch (const cv::Exception& e) {
    return make_error(ErrorCode::kIoError, "{}: cannot write ({})", path.string(),
                      opencv_reason(e));
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) return make_error(ErrorCode::kIoError, "{}: {}", path.string(), ec.message());
  return ok_status();
}

namespace {
Error corrupt(const fs::path& path, const std::string& what) {
  return Error{ErrorCode::kCorruptData,
               fmt::format("{}: not a valid voice model ({})", path.string(), what)};
}
}  // namespace

Result<VoiceModel> VoiceModel::load(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    return make_error(ErrorCode::kNotFound,
                      "{}: voice model missing (write one with `dreamsense train voices`)",
                      path.string());
  DS_ASSIGN_OR_RETURN(cv::FileStorage f, open_file_storage(path));
  VoiceModel m;
  try {
    std::string format;
    int version = 0;
    if (f["format"].isString()) f["format"] >> format;
    if (format != kFormatName)
      return tl::unexpected(
          corrupt(path, fmt::format("format is '{}', expected '{}'", format, kFormatName)));
    f["version"] >> version;
    if (version != kFormatVersion)
      return make_error(ErrorCode::kUnsupported,
                        "{}: voice model format version {} is not supported (this build reads "
                        "version {})",
                        path.string(), version, kFormatVersion);
    const cv::FileNode fe = f["features"];
    if (!fe.isMap()) return tl::unexpected(corrupt(path, "no features section"));
    auto flag = [&](const char* key, bool& out) {
      int v = out ? 1 : 0;
      if (!fe[key].empty()) fe[key] >> v;
      out = v != 0;
    };
    auto num = [&](const char* key, auto& out) {
      if (fe[key].empty()) throw std::runtime_error(std::string("features.") + key + " missing");
      fe[key] >> out;
    };
    num("frame_s", m.features.frame_s);
    num("hop_s", m.features.hop_s);
    num("preemphasis", m.features.preemphasis);
    num("filters", m.features.filters);
    num("cepstra", m.features.cepstra);
    num("low_hz", m.features.low_hz);
    num("high_hz", m.features.high_hz);
    num("delta_window", m.features.delta_window);
    num("drop_below_peak_db", m.features.drop_below_peak_db);
    num("above_floor_db", m.features.above_floor_db);
    num("min_level_db", m.features.min_level_db);
    flag("delta_deltas", m.features.delta_deltas);
    flag("static_energy", m.features.static_energy);
    flag("mean_normalise", m.features.mean_normalise);
    flag("variance_normalise", m.features.variance_normalise);
    flag("noise_suppression", m.features.noise_suppression);  // absent (older files): off
    num("cmn_prior_frames", m.features.cmn_prior_frames);
    if (!f["cmn_prior"].empty()) {
      cv::Mat prior;
      f["cmn_prior"] >> prior;
      prior.convertTo(m.cmn_prior, CV_64F);
    }
    if (const cv::FileNode mp = f["map"]; mp.isMap()) {
      int w = 1, v = 1;
      mp["relevance"] >> m.map.relevance;
      mp["adapt_weights"] >> w;
      mp["adapt_variances"] >> v;
      mp["variance_floor"] >> m.map.variance_floor;
      m.map.adapt_weights = w != 0;
      m.map.adapt_variances = v != 0;
    }
    f["threshold"] >> m.threshold;
    f["score_scale"] >> m.score_scale;
    f["background"] >> m.background;
    const cv::FileNode u = f["ubm"];
    if (!u.isMap()) return tl::unexpected(corrupt(path, "no ubm section"));
    cv::Mat w, mu, var;
    u["weights"] >> w;
    u["means"] >> mu;
    u["variances"] >> var;
    auto g = DiagonalGmm::create(w, mu, var);
    if (!g) return tl::unexpected(corrupt(path, "ubm: " + g.error().message));
    m.ubm = std::move(*g);
    const cv::FileNode sp = f["speakers"];
    if (!sp.isSeq()) return tl::unexpected(corrupt(path, "no speakers list"));
    for (const auto& n : sp) {
      EnrolledSpeaker s;
      n["id"] >> s.id;
      n["name"] >> s.name;
      n["utterances"] >> s.utterances;
      n["frames"] >> s.frames;
      cv::Mat w, mu, var;
      n["weights"] >> w;
      n["means"] >> mu;
      n["variances"] >> var;
      auto g = DiagonalGmm::create(w, mu, var);
      if (!g) return tl::unexpected(corrupt(path, "speaker '" + s.id + "': " + g.error().message));
      s.model = std::move(*g);
      if (s.name.empty()) s.name = s.id;
      m.speakers.push_back(std::move(s));
    }
  } catch (const cv::Exception& e) {
    std::string what = e.err.empty() ? std::string("YAML parse error") : e.err;
    std::replace(what.begin(), what.end(), '\n', ' ');
    return tl::unexpected(corrupt(path, what));
  } catch (const std::exception& e) {
    return tl::unexpected(corrupt(path, e.what()));
  }
  if (auto s = m.check(); !s) return tl::unexpected(corrupt(path, s.error().message));
  return m;
}

namespace {
// Un-normalised features of one recording, through the noise suppressor when the options say so.
Result<MfccFeatures> features_of(const LabelledAudio& a, const MfccOptions& o) {
  if (!o.noise_suppression) return unnormalised_mfcc(a.samples, a.sample_rate, o);
  // One pass, as the analyser's streaming filter: enrolment and scoring see the same processing.
  DS_ASSIGN_OR_RETURN(auto clean, audio::suppress_noise(a.samples, a.sample_rate, {}, 1));
  return unnormalised_mfcc(clean, a.sample_rate, o);
}
}  // namespace

Result<VoiceModel> train_voice_model(const std::vector<LabelledAudio>& enrolment,
                                     const std::vector<LabelledAudio>& background,
                                     const VoiceTrainOptions& o, const std::string& background_note,
                                     const std::function<void(double)>& progress) {
  if (auto s = o.check(); !s) return tl::unexpected(s.error());
  if (enrolment.empty())
    return make_error(ErrorCode::kInvalidArgument, "train voices: no enrolment recordings");
  const size_t steps = enrolment.size() + background.size();
  size_t done = 0;
  auto tick = [&] {
    if (progress) progress(0.3 * static_cast<double>(++done) / static_cast<double>(steps));
  };
  // Un-normalised features of every recording first: the prior mean for the normalisation is
  // the background's (the pooled enrolment's when no background is given).
  std::vector<std::string> order;
  std::map<std::string, std::vector<cv::Mat>> per_speaker;
  std::map<std::string, int> utterances;
  for (const auto& a : enrolment) {
    if (a.speaker.empty() || a.speaker == kUnknownSpeaker)
      return make_error(ErrorCode::kInvalidArgument, "train voices: {}: invalid speaker '{}'",
                        a.source, a.speaker);
    auto f = features_of(a, o.features);
    if (!f) return make_error(f.error().code, "train voices: {}: {}", a.source, f.error().message);
    if (!per_speaker.count(a.speaker)) order.push_back(a.speaker);
    per_speaker[a.speaker].push_back(f->frames);
    utterances[a.speaker]++;
    tick();
  }
  std::vector<cv::Mat> bg_list;
  if (background.empty()) {
    for (const auto& id : order)
      for (const auto& m : per_speaker[id])
        if (m.rows > 0) bg_list.push_back(m);
  } else {
    for (const auto& a : background) {
      auto f = features_of(a, o.features);
      if (!f)
        return make_error(f.error().code, "train voices: background {}: {}", a.source,
                          f.error().message);
      if (f->frames.rows > 0) bg_list.push_back(f->frames);
      tick();
    }
    if (bg_list.empty())
      return make_error(ErrorCode::kInvalidArgument,
                        "train voices: the background recordings hold no speech");
  }
  cv::Mat prior;
  if (!bg_list.empty()) {
    cv::Mat all;
    cv::vconcat(bg_list, all);
    cv::reduce(all, prior, 0, cv::REDUCE_AVG, CV_64F);
  }
  // Normalise every recording, then pool.
  cv::Mat bg;
  {
    std::vector<cv::Mat> normalised;
    for (auto& m : bg_list) {
      cv::Mat x = m.clone();
      normalise_features(x, o.features, prior);
      normalised.push_back(x);
    }
    if (!normalised.empty()) cv::vconcat(normalised, bg);
  }
  std::map<std::string, cv::Mat> frames;
  for (const auto& id : order) {
    std::vector<cv::Mat> list;
    for (const auto& m : per_speaker[id]) {
      cv::Mat x = m.clone();
      normalise_features(x, o.features, prior);
      if (x.rows > 0) list.push_back(x);
    }
    if (list.empty())
      return make_error(ErrorCode::kInvalidArgument,
                        "train voices: speaker '{}': its {} recording(s) hold no speech", id,
                        utterances[id]);
    cv::vconcat(list, frames[id]);
  }
  auto ubm = train_gmm(bg, o.ubm, [&](double f) {
    if (progress) progress(0.3 + 0.6 * f);
  });
  if (!ubm)
    return make_error(ubm.error().code, "train voices: background model: {}", ubm.error().message);
  VoiceModel m;
  m.features = o.features;
  m.cmn_prior = prior;
  m.ubm = std::move(*ubm);
  m.map = o.map;
  m.threshold = o.threshold;
  m.score_scale = o.score_scale;
  m.background =
      !background_note.empty() ? background_note
      : background.empty()
          ? fmt::format("enrolment recordings pooled ({} frames)", bg.rows)
          : fmt::format("{} background recordings ({} frames)", background.size(), bg.rows);
  for (const auto& id : order) {
    EnrolledSpeaker s;
    s.id = id;
    s.name = id;
    s.utterances = utterances[id];
    s.frames = frames[id].rows;
    s.model = map_adapt(m.ubm, frames[id], o.map);
    m.speakers.push_back(std::move(s));
  }
  if (progress) progress(1.0);
  if (auto s = m.check(); !s) return tl::unexpected(s.error());
  return m;
}

Identification identify_features(const VoiceModel& model, const cv::Mat& features) {
  Identification r;
  r.frames = features.rows;
  r.speaker_id = kUnknownSpeaker;
  r.name = kUnknownSpeaker;
  if (features.rows == 0 || model.speakers.empty()) return r;
  const std::vector<double> ubm_ll = model.ubm.frame_log_likelihoods(features);
  double ubm_mean = 0;
  for (double v : ubm_ll) ubm_mean += v;
  ubm_mean /= static_cast<double>(ubm_ll.size());
  for (const auto& s : model.speakers) {
    const std::vector<double> ll = s.model.frame_log_likelihoods(features);
    double mean = 0;
    for (double v : ll) mean += v;
    mean /= static_cast<double>(ll.size());
    r.scores.push_back({s.id, mean - ubm_mean});
  }
  std::stable_sort(r.scores.begin(), r.scores.end(),
                   [](const SpeakerScore& a, const SpeakerScore& b) { return a.llr > b.llr; });
  r.best_id = r.scores.front().id;
  r.llr = r.scores.front().llr;
  const double p = 1.0 / (1.0 + std::exp(-(r.llr - model.threshold) / model.score_scale));
  if (r.llr >= model.threshold) {
    r.speaker_id = r.best_id;
    for (const auto& s : model.speakers)
      if (s.id == r.best_id) r.name = s.name;
    r.score = p;
  } else {
    r.score = 1.0 - p;
  }
  return r;
}

bool is_role_speaker_id(std::string_view id) {
  return id == "child" || id == "therapist" || id == kUnknownSpeaker;
}

std::string public_speaker_id(const VoiceModel& model, const std::string& speaker_id) {
  if (speaker_id == kUnknownSpeaker) return kUnknownSpeaker;
  for (size_t k = 0; k < model.speakers.size(); ++k)
    if (model.speakers[k].id == speaker_id)
      return is_role_speaker_id(speaker_id) ? speaker_id : fmt::format("speaker_{}", k + 1);
  return kUnknownSpeaker;
}

Result<Identification> identify(const VoiceModel& model, std::span<const float> samples,
                                int sample_rate, bool denoised) {
  if (model.features.noise_suppression && !denoised) {
    DS_ASSIGN_OR_RETURN(auto clean, audio::suppress_noise(samples, sample_rate, {}, 1));
    return identify(model, clean, sample_rate, true);
  }
  auto f = compute_mfcc(samples, sample_rate, model.features, model.cmn_prior);
  if (!f) return tl::unexpected(f.error());
  return identify_features(model, f->frames);
}

}  // namespace dreamsense::voice_id
