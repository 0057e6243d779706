#include "dreamsense/live/live_analysis.hpp"

#include "dreamsense/core/log.hpp"
#include "dreamsense/self_calibration/live.hpp"

#include <atomic>
#include <chrono>
#include <csignal>
#include <memory>
#include <thread>

#include "operator_feed.hpp"

namespace dreamsense::live {
namespace {
std::atomic<bool> g_stop_live{false};
extern "C" void on_live_stop_signal(int /*signal*/) { g_stop_live = true; }
}  // namespace

Result<LiveAnalysisSummary> run_live_analysis(const LiveAnalysisOptions& options) {
  DS_ASSIGN_OR_RETURN(const sources::RecordConfig config,
                      sources::read_record_config(options.config));
  std::unique_ptr<publish::DdsPublisher> publisher;
  if (options.dds) {
    publish::DdsPublisherOptions po = *options.dds;
    // Sizes to normalise face boxes by (/humans/faces/<id>/roi): the requested camera sizes.
    for (const auto& c : config.cameras)
      if (c.width > 0 && c.height > 0 && !po.image_sizes.count(c.id))
        po.image_sizes[c.id] = cv::Size(c.width, c.height);
    DS_ASSIGN_OR_RETURN(publisher, publish::DdsPublisher::create(po));
  }
  runner::AnalysisOptions o = options.analysis;
  std::unique_ptr<ui::OperatorPage> page;
  std::unique_ptr<OperatorFeed> feed;  // the page's pictures, status strip and markers
  if (options.ui) {
    DS_ASSIGN_OR_RETURN(page, ui::OperatorPage::start(*options.ui));
    if (options.on_ui_started) options.on_ui_started(page->url());
    feed = std::make_unique<OperatorFeed>(*page, o.evaluator.offline_after);
    feed->attach(o);
    if (!o.csv) o.csv = true;  // the page's markers go into tables/events.csv
  }
  if (publisher || page)
    o.on_records = [&publisher, &page](const std::vector<primitives::PrimitiveRecord>& records) {
      if (page) page->update(records);
      return publisher ? publisher->publish(records) : ok_status();
    };
  // With a --duration the run lasts that long even when every device (a video file) ends first.
  sources::LiveCaptureOptions capture_options;
  capture_options.until_stopped = options.duration_s > 0;
  DS_ASSIGN_OR_RETURN(auto capture,
                      sources::LiveCapture::open(config, options.record, {}, capture_options));
  if (feed) feed->set_capture(*capture, options.record);
  // A new child: self-calibrated while the session runs (issue 15), when the analysis writes an
  // output folder for its files.
  std::unique_ptr<self_calibration::LiveSelfCalibration> calibration;
  if (!o.out_dir.empty() && self_calibration::needs_self_calibration(o.plan, capture->manifest(),
                                                                     options.self_calibration)) {
    self_calibration::LiveSelfCalibrationOptions lo;
    DS_ASSIGN_OR_RETURN(lo.search, self_calibration::self_calibration_options(
                                       o.plan, options.self_calibration_overrides, &lo));
    lo.work_dir = o.out_dir / "self_calibration";
    DS_ASSIGN_OR_RETURN(calibration, self_calibration::LiveSelfCalibration::start(
                                         capture->manifest(), std::filesystem::current_path(), lo));
    const auto subject = capture->manifest().metadata.find("subject");
    log::info(
        "live: no calibration for subject '{}': self-calibrating during the session (generic "
        "face model and gaze constants until it converges)",
        subject == capture->manifest().metadata.end() ? "" : subject->second);
    if (options.self_calibration == self_calibration::SelfCalibrationMode::kAlways)
      o.plan.subject_from_session = false;
    o.live_subject_models = [c = calibration.get()](const MultiFrame& tick) {
      return c->offer(tick);
    };
    if (feed) feed->set_face_model_status([c = calibration.get()] { return c->model_in_use(); });
    o.report_calibration = [c = calibration.get()] {
      return self_calibration::report_lines(c->status());
    };
  }
  g_stop_live = false;
  if (options.stop_on_signals) {
    std::signal(SIGINT, on_live_stop_signal);
    std::signal(SIGTERM, on_live_stop_signal);
  }
  if (options.on_capture_started) options.on_capture_started();
  std::atomic<bool> analysis_done{false};
  std::atomic<bool> analysis_ready{false};
  o.on_ready = [&analysis_ready] { analysis_ready = true; };
  Result<runner::AnalysisSummary> result = make_error(ErrorCode::kInternal, "not run");
  std::thread analysis([&] {
    result = runner::analyze_live(o, *capture);
    analysis_done = true;
    capture->stop();  // an analysis error ends the capture too
  });
  // --duration counts analysed time: from when the analysers are ready (models loaded), so a
  // slow start does not eat it.
  while (!analysis_done && !analysis_ready && !g_stop_live)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  const auto start = std::chrono::steady_clock::now();
  while (!analysis_done && !g_stop_live &&
         !(options.duration_s > 0 &&
           std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >=
               options.duration_s))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  capture->stop();
  analysis.join();
  if (feed) feed->end();
  if (options.stop_on_signals) {
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
  }
  auto stats = capture->finish();
  if (!result) return tl::unexpected(result.error());
  if (!stats) return tl::unexpected(stats.error());
  LiveAnalysisSummary s;
  s.analysis = std::move(*result);
  s.capture = std::move(*stats);
  if (publisher) s.dds = publisher->stats();
  // The capture's per-stream counts, and what a lost device cost, for whoever reads the analysis
  // later (the terminal only sees them once).
  if (!o.out_dir.empty())
    DS_RETURN_IF_ERROR(
        runner::add_to_summary(o.out_dir, "live_capture", sources::capture_report(s.capture)));
  if (calibration) {
    nlohmann::json j = calibration->status();
    calibration.reset();  // the search stops
    if (options.save_live_self_calibration && j.value("state", "") == "converged") {
      DS_ASSIGN_OR_RETURN(const std::filesystem::path saved,
                          self_calibration::save_subject_folder(
                              o.out_dir / "self_calibration", o.plan.subjects_dir,
                              capture->manifest().metadata, "live configuration"));
      j["saved_to"] = saved.string();
      // The live gaze learnt its sideways correction with these eyeballs (from the switch on).
      DS_RETURN_IF_ERROR(self_calibration::save_learnt_fixation_yaw(j, s.analysis));
    }
    DS_RETURN_IF_ERROR(runner::add_to_summary(o.out_dir, "live_self_calibration", j));
    s.self_calibration = std::move(j);
  }
  return s;
}

}  // namespace dreamsense::live
