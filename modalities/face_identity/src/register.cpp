// Declared pipeline entry of the face identity analyser (perception/analyzer_registry.hpp).

#include "dreamsense/face_identity/face_identity_analyzer.hpp"
#include "dreamsense/perception/analyzer_registry.hpp"

namespace dreamsense::face_identity {

void register_analyzers(AnalyzerRegistry& registry) {
  AnalyzerFactory f;
  f.name = "face_identity";
  f.summary =
      "who the selected face is, against an enrolment gallery (face-api.js descriptor or "
      "Tan-Triggs multi-scale LBP; unknown rejection chosen on the enrolment data)";
  f.roles = {roles::kChildCamera};
  f.plan = [](const PlanContext& ctx, OptionsNode& options) -> Result<PlannedAnalyzers> {
    FaceIdentityAnalyzerOptions o;
    DS_RETURN_IF_ERROR(options.get("gallery", o.gallery));
    DS_RETURN_IF_ERROR(options.get("refresh_s", o.refresh_s));
    o.include_names = ctx.include_names;
    std::string where = "option gallery";
    // Where the gallery comes from: the option, the session's metadata `face_gallery`, or the
    // child's subject folder (face_gallery.yaml).
    if (o.gallery.empty()) {
      DS_ASSIGN_OR_RETURN(auto meta, ctx.metadata_file("face_gallery"));
      if (meta) {
        o.gallery = *meta;
        where = "session metadata face_gallery";
      }
    }
    if (o.gallery.empty() && !ctx.subject.folder.empty() &&
        std::filesystem::exists(ctx.subject.folder / "face_gallery.yaml")) {
      o.gallery = ctx.subject.folder / "face_gallery.yaml";
      where = "subject folder";
    }
    if (o.gallery.empty())
      return PlannedAnalyzers::skip(
          "no face gallery (option gallery, session metadata face_gallery or the subject "
          "folder's face_gallery.yaml; dreamsense enroll faces)");
    const auto cameras = ctx.cameras_with_role(roles::kChildCamera);
    if (cameras.empty())
      return PlannedAnalyzers::skip("no calibrated stream with role child_camera");
    for (const auto& [id, m] : cameras) o.cameras.push_back(id);
    auto analyzer = make_face_identity_analyzer(o);
    // A gallery found by default (not asked for) whose network weights are not installed: the
    // analyser is left out with the reason (--print-pipeline), the rest of the analysis runs.
    if (!analyzer && where != "option gallery" && analyzer.error().code == ErrorCode::kNotFound &&
        std::filesystem::exists(o.gallery))
      return PlannedAnalyzers::skip(analyzer.error().message);
    if (!analyzer) return tl::unexpected(analyzer.error());
    PlannedAnalyzers p;
    // The gallery's folder may be named after the person (a subject folder): its file name only
    // unless names are asked for.
    p.notes.push_back("gallery " +
                      (ctx.include_names ? o.gallery.string() : o.gallery.filename().string()) +
                      " (" + where + ")");
    p.analyzers.push_back(std::move(*analyzer));
    return p;
  };
  registry.add(std::move(f));
}

}  // namespace dreamsense::face_identity
