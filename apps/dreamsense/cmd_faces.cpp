// Face verbs (issue 12): expression (F18 identifyFaceExpression) and identity (F17 identifyFace).
//   dreamsense train expression --dataset ckplus48|fer2013 DIR --out MODEL.yaml [--method M]
//   dreamsense eval expression [--model MODEL.yaml] --dataset ckplus48|fer2013 DIR
//                              [--methods a,b] [--folds K] [--json FILE|-]
//     fer2013 without --model/--methods/--folds: the model the pipeline ships (issue 20);
//     ckplus48 without them: cross-validation (spec/cli.md).
//   dreamsense enroll faces --person ID IMAGES... --gallery FILE [--name NAME] [--method M]
//   dreamsense eval faces --dataset att|yale DIR --enroll K [--unknown U] [--methods a,b]
// Thin: flags -> options -> eval_faces / face_identity -> report.

#include "dreamsense/eval/faces/expression_eval.hpp"
#include "dreamsense/eval/faces/identity_eval.hpp"
#include "dreamsense/expression/expression_analyzer.hpp"
#include "dreamsense/face_identity/face_gallery.hpp"
#include "dreamsense/sources/session.hpp"
#include "dreamsense/vision/face_locator.hpp"
#include "dreamsense/vision/image_io.hpp"

#include <cstdio>

#include "commands.hpp"
#include "progress.hpp"

namespace dreamsense::app {
namespace {

const char* kExpressionDatasetHelp =
    "NAME DIR; NAME: ckplus48 (DIR/<emotion>/S###_###_########.png) or fer2013 "
    "(DIR/<class>/*.jpg, 48x48 faces in the wild)";

double get_or(const nlohmann::json& j, const char* key) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : -1.0;
}

struct TrainExpressionFlags {
  std::vector<std::string> dataset;
  std::string out;
  eval::faces::ExpressionTrainOptions options;
};

struct EvalExpressionFlags {
  std::vector<std::string> dataset;
  std::string json, model;
  eval::faces::ExpressionEvalOptions options;
};

struct EvalFacesFlags {
  std::vector<std::string> dataset;
  std::string json;
  eval::faces::FaceIdEvalOptions options;
};

struct EnrollFacesFlags {
  int person = -1;
  std::string name, gallery, method = "face_api";
  std::vector<std::string> images;
  // --session: frames of a recorded session instead of images.
  std::string session, stream;
  int every = 25, max_frames = 20;
};

// Grey frames of `stream` in a session (every `every`-th, at most `max` of them) for enrolment.
Result<std::vector<std::pair<std::string, cv::Mat>>> session_frames(const EnrollFacesFlags& f) {
  auto reader = sources::SessionReader::open(f.session);
  if (!reader) return tl::unexpected(reader.error());
  std::string stream = f.stream;
  if (stream.empty())
    for (const auto& e : (*reader)->manifest().streams)
      if (e.kind == SensorKind::kColor) {
        stream = e.id;
        break;
      }
  std::vector<std::pair<std::string, cv::Mat>> out;
  for (int index = 0; static_cast<int>(out.size()) < f.max_frames;) {
    auto frame = (*reader)->next();
    if (!frame) {
      if (frame.error().code == ErrorCode::kEndOfStream) break;
      return tl::unexpected(frame.error());
    }
    if ((*frame)->sensor != stream) continue;
    const ColorImage* img = (*frame)->as<ColorImage>();
    if (img == nullptr)
      return make_error(ErrorCode::kInvalidArgument, "{}: stream '{}' is not a colour stream",
                        f.session, stream);
    if (index++ % f.every != 0) continue;
    auto grey = vision::to_grey(img->image);
    if (!grey) return tl::unexpected(grey.error());
    out.emplace_back(fmt::format("{}:{}@{:.2f}s", f.session, stream, (*frame)->stamp.seconds()),
                     grey->clone());
  }
  if (out.empty())
    return make_error(ErrorCode::kNotFound, "{}: no frames of a colour stream '{}'", f.session,
                      stream);
  return out;
}

// Adds the images of one person to a gallery file (created when missing).
Status enroll_faces(const EnrollFacesFlags& f, bool quiet) {
  face_identity::FaceGallery gallery;
  if (std::filesystem::exists(f.gallery)) {
    auto g = face_identity::FaceGallery::load(f.gallery);
    if (!g) return tl::unexpected(g.error());
    if (g->method().name != f.method)
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: gallery uses method {} (not {}); enrol with --method {} or use a new "
                        "gallery file",
                        f.gallery, g->method().name, f.method, g->method().name);
    gallery = std::move(*g);
  } else {
    auto m = face_identity::identity_method(f.method);
    if (!m) return tl::unexpected(m.error());
    gallery = face_identity::FaceGallery(*m);
  }
  auto extractor = face_identity::IdentityFeatureExtractor::create(gallery.method());
  if (!extractor) return tl::unexpected(extractor.error());
  if (gallery.empty())
    gallery = face_identity::FaceGallery(gallery.method(), extractor->weights_hash());
  if (auto s = face_identity::check_compatible(gallery, *extractor); !s)
    return make_error(s.error().code, "{}: {}", f.gallery, s.error().message);
  vision::FaceCropOptions crop;
  crop.alignment = gallery.method().alignment;
  std::vector<std::pair<std::string, cv::Mat>> images;
  if (!f.session.empty()) {
    // Whole camera frames: search at full resolution for a face of >= 1/12 of the shorter side
    // (the largest face is enrolled; frames without one are skipped).
    auto frames = session_frames(f);
    if (!frames) return tl::unexpected(frames.error());
    images = std::move(*frames);
    crop.assume_crop = false;
    crop.working_px = std::min(images.front().second.rows, images.front().second.cols);
    crop.min_face_fraction = 1.0 / 12;
  } else {
    for (const std::string& path : f.images) {
      auto grey = vision::read_grey_image(path);
      if (!grey) return tl::unexpected(grey.error());
      images.emplace_back(path, std::move(*grey));
    }
  }
  auto landmarker = vision::load_landmarker();
  if (!landmarker) return tl::unexpected(landmarker.error());
  auto aligner = vision::make_face_crop_aligner(crop, *landmarker);
  if (!aligner) return tl::unexpected(aligner.error());
  size_t enrolled = 0;
  for (const auto& [path, grey] : images) {
    auto face = aligner->align(grey);
    if (!face) return make_error(face.error().code, "{}: {}", path, face.error().message);
    // Enrolment needs landmarks: a guessed crop geometry would enrol whatever the image shows.
    if (!*face || (*face)->source == vision::AlignmentSource::kCropGeometry) {
      if (!f.session.empty()) continue;  // a session frame without a visible face
      return make_error(ErrorCode::kInvalidArgument,
                        "{}: no face found (enrolment needs a visible, roughly frontal face)",
                        path);
    }
    if (auto s = gallery.add(f.person, extractor->extract(grey, **face)); !s)
      return tl::unexpected(s.error());
    ++enrolled;
  }
  if (enrolled == 0)
    return make_error(ErrorCode::kNotFound, "{}: no face found in {} frames", f.session,
                      images.size());
  if (!f.name.empty()) gallery.set_name(f.person, f.name);
  if (auto s = gallery.save(f.gallery); !s) return s;
  if (!quiet)
    std::fprintf(
        stderr,
        "faces: enrolled %zu images of person %d; gallery %s holds %zu persons, %zu images\n",
        enrolled, f.person, f.gallery.c_str(), gallery.persons().size(), gallery.images());
  return ok_status();
}

}  // namespace

void add_enroll_faces(CLI::App& enroll, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<EnrollFacesFlags>();
  CLI::App* cmd = enroll.add_subcommand(
      "faces", "Add face images of one person to a face gallery (descriptors, not photos)");
  cmd->add_option("--person", flags->person, "Person id (>= 0; identifyFace answers it)")
      ->required()
      ->check(CLI::NonNegativeNumber);
  auto* images = cmd->add_option("images", flags->images, "Face images (photos or face crops)");
  auto* session = cmd->add_option(
      "--session", flags->session,
      "Enrol from a recorded session's frames instead (the largest face of every --every-th "
      "frame of --stream)");
  images->excludes(session);
  session->excludes(images);
  cmd->add_option("--stream", flags->stream, "With --session: colour stream (default: the first)");
  cmd->add_option("--every", flags->every, "With --session: use every N-th frame")
      ->default_val(flags->every)
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-frames", flags->max_frames, "With --session: at most this many frames")
      ->default_val(flags->max_frames)
      ->check(CLI::PositiveNumber);
  cmd->add_option("--gallery", flags->gallery, "Gallery file (created when missing)")->required();
  cmd->add_option("--name", flags->name,
                  "Store this name for the id (by default the gallery holds ids only)");
  cmd->add_option("--method", flags->method,
                  "face_api (pretrained descriptor, default), lbp_tt (classical) or lbp_svm "
                  "(DREAM's seed)")
      ->default_val(flags->method);
  cmd->callback([flags, &g, &exit_code] {
    if (flags->images.empty() && flags->session.empty()) {
      exit_code = fail(std::string("enroll faces: give face images or --session DIR"));
      return;
    }
    if (auto s = enroll_faces(*flags, g.quiet); !s) exit_code = fail(s.error());
  });
}

void add_eval_faces(CLI::App& eval, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<EvalFacesFlags>();
  auto& o = flags->options;
  CLI::App* cmd = eval.add_subcommand(
      "faces", "Face identification with unknown rejection: accuracy, false_accept_rate");
  cmd->add_option("--dataset", flags->dataset,
                  "NAME DIR; NAME: att (DIR/sN/M.pgm) or yale (DIR/subjectNN.condition)")
      ->expected(2)
      ->required();
  cmd->add_option("--enroll", o.enroll, "First K images of each subject enrol")->required();
  cmd->add_option("--unknown", o.unknown,
                  "The last U subjects never enrol; their images must be rejected")
      ->default_val(o.unknown);
  cmd->add_option("--methods", o.methods, "Methods compared in the same run (first = top level)")
      ->delimiter(',')
      ->default_str("face_api,lbp_tt,lbp_svm");
  cmd->add_option("--json", flags->json, "Write the evaluation JSON to FILE (- for stdout)");
  cmd->callback([flags, &g, &exit_code] {
    auto& o = flags->options;
    o.dataset = flags->dataset[0];
    o.dir = flags->dataset[1];
    auto r = with_progress("eval faces", g.quiet, [&](const auto& progress) {
      return eval::faces::run_face_id_eval(o, progress);
    });
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (!g.quiet) {
      std::fprintf(stderr, "faces: %zu probes; %s\n", r->items, r->protocol.c_str());
      for (const auto& m : r->extra.at("methods")) {
        const std::string name = m.get<std::string>();
        const auto& mm = r->metrics[name];
        std::fprintf(
            stderr,
            "  %-10s accuracy %.4f  false_accept_rate %.4f  closed-set %.4f  ms/face %.3f\n",
            name.c_str(), get_or(mm, "accuracy"), get_or(mm, "false_accept_rate"),
            get_or(mm, "closed_set_accuracy"), get_or(r->timing[name], "ms_per_face_median"));
      }
    }
    if (auto s = eval::write_report(*r, flags->json); !s) exit_code = fail(s.error());
  });
}

void add_train_expression(CLI::App& train, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<TrainExpressionFlags>();
  CLI::App* cmd = train.add_subcommand(
      "expression", "Facial expression model (identifyFaceExpression) from a labelled face set");
  cmd->add_option("--dataset", flags->dataset, kExpressionDatasetHelp)->expected(2)->required();
  cmd->add_option("--out", flags->out, "Model file to write (YAML)")->required();
  cmd->add_option("--method", flags->options.method,
                  "lbp_hog (classical, default), lbp_svm (DREAM's seed), face_api (network "
                  "features, npm @vladmandic/face-api), fusion (both)")
      ->default_val(flags->options.method);
  cmd->callback([flags, cmd, &g, &exit_code] {
    auto& o = flags->options;
    o.dataset = flags->dataset[0];
    o.dir = flags->dataset[1];
    o.note = fmt::format("dreamsense train expression --dataset {} {} --method {}", o.dataset,
                         o.dir.filename().string(), o.method);
    eval::faces::ExpressionTrainSummary summary;
    auto m = with_progress("train expression", g.quiet, [&](const auto& progress) {
      return eval::faces::run_expression_train(o, &summary, progress);
    });
    if (!m) {
      exit_code = fail(m.error());
      return;
    }
    if (auto s = m->save(flags->out); !s) {
      exit_code = fail(s.error());
      return;
    }
    if (!g.quiet) {
      std::string per;
      for (const auto& [label, n] : summary.per_label)
        per += fmt::format("{}{} {}", per.empty() ? "" : ", ", label, n);
      std::fprintf(stderr, "expression: method %s trained on %zu of %zu images (%s); wrote %s\n",
                   o.method.c_str(), summary.used, summary.images, per.c_str(), flags->out.c_str());
    }
    (void)cmd;
  });
}

void add_eval_expression(CLI::App& eval, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<EvalExpressionFlags>();
  auto& o = flags->options;
  CLI::App* cmd = eval.add_subcommand(
      "expression",
      "Facial expression: accuracy, per-class recall, confusion (subject-disjoint CV, or a model)");
  cmd->add_option("--dataset", flags->dataset, kExpressionDatasetHelp)->expected(2)->required();
  cmd->add_option("--model", flags->model,
                  "Test this model (train expression) on every image (default: fer2013 tests the "
                  "model the pipeline ships; ckplus48, or --methods/--folds: cross-validation)");
  cmd->add_option("--methods", o.methods,
                  "Cross-validation: methods compared on the same folds, the first one reported "
                  "at the top level")
      ->delimiter(',')
      ->default_str("lbp_hog,lbp_svm");
  cmd->add_option("--folds", o.folds, "Cross-validation folds (subject-disjoint)")
      ->default_val(o.folds);
  cmd->add_option("--seed", o.seed, "Seed of the fold assignment")->default_val(o.seed);
  cmd->add_option("--json", flags->json, "Write the evaluation JSON to FILE (- for stdout)");
  cmd->callback([flags, cmd, &g, &exit_code] {
    auto& o = flags->options;
    o.dataset = flags->dataset[0];
    o.dir = flags->dataset[1];
    o.model = flags->model;
    // Faces in the wild check what the pipeline answers: its shipped model, through the same
    // alignment; cross-validation of methods stays available with --methods/--folds.
    const bool cross_validation = cmd->count("--methods") > 0 || cmd->count("--folds") > 0;
    if (o.model.empty() && o.dataset == "fer2013" && !cross_validation)
      o.model = expression::default_expression_model();
    auto r = with_progress("eval expression", g.quiet, [&](const auto& progress) {
      return eval::faces::run_expression_eval(o, progress);
    });
    if (!r) {
      exit_code = fail(r.error());
      return;
    }
    if (!g.quiet) {
      std::string line = fmt::format("expression: {} images, {}", r->items, r->protocol);
      std::fprintf(stderr, "%s\n", line.c_str());
      for (const auto& m : r->extra.at("methods")) {
        const std::string name = m.get<std::string>();
        const nlohmann::json& mm = r->metrics.contains(name) ? r->metrics[name] : r->metrics;
        const nlohmann::json& tt = r->timing.contains(name) ? r->timing[name] : r->timing;
        std::fprintf(stderr, "  %-10s accuracy %.4f  balanced %.4f  ms/face %.3f\n", name.c_str(),
                     get_or(mm, "accuracy"), get_or(mm, "balanced_accuracy"),
                     get_or(tt, "ms_per_face_median"));
      }
      std::string recalls;
      for (const auto& [label, c] : r->per_class.items())
        if (c.contains("recall") && c["recall"].is_number())
          recalls += fmt::format(" {} {:.2f}", label, c["recall"].get<double>());
      std::fprintf(stderr, "  recall:%s\n", recalls.c_str());
      if (r->extra.contains("classes_missing_from_model"))
        for (const auto& l : r->extra.at("classes_missing_from_model"))
          std::fprintf(stderr, "  class %s: the model has no such label (counted wrong)\n",
                       l.get<std::string>().c_str());
    }
    if (auto s = eval::write_report(*r, flags->json); !s) exit_code = fail(s.error());
  });
}

}  // namespace dreamsense::app
