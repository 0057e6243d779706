// dreamsense: multi-sensory perception for robot-enhanced therapy. One executable, verbs as
// subcommands (../shared/spec/cli.md).

#include "dreamsense/core/log.hpp"

#include <cstdio>
#include <fstream>
#include <iostream>

#include "commands.hpp"

namespace dreamsense::app {

int fail(const Error& e) { return fail(e.message); }

int fail(const std::string& message) {
  std::string one_line = message;
  std::replace(one_line.begin(), one_line.end(), '\n', ' ');
  std::fprintf(stderr, "error: %s\n", one_line.c_str());
  return kExitFailure;
}

Status write_json(const std::string& target, const nlohmann::json& j) {
  if (target.empty()) return ok_status();
  const std::string text = j.dump(2) + "\n";
  if (target == "-") {
    std::cout << text << std::flush;
    return ok_status();
  }
  std::ofstream out(target);
  if (!out) return make_error(ErrorCode::kIoError, "{}: cannot write", target);
  out << text;
  if (!out) return make_error(ErrorCode::kIoError, "{}: write failed", target);
  return ok_status();
}

}  // namespace dreamsense::app

int main(int argc, char** argv) {
  using namespace dreamsense;
  CLI::App app{"dreamsense: open multi-sensory perception for robot-enhanced therapy (DREAM D4.2)"};
  app.set_version_flag("--version", std::string(DREAMSENSE_VERSION));
  app.require_subcommand(1);
  app.fallthrough();  // global flags (-q, -v) also after the verb
  app::GlobalFlags g;
  app.add_flag("-q,--quiet", g.quiet,
               "Print nothing but errors (no progress bar, no summary, no warnings)");
  app.add_flag("-v,--verbose", g.verbose, "Debug logging");
  int exit_code = app::kExitOk;
  app::add_demo(app, g, exit_code);
  app::add_analyze(app, g, exit_code);
  app::add_batch(app, g, exit_code);  // cmd_batch.cpp
  app::add_check(app, g, exit_code);  // cmd_check.cpp
  app::add_eval(app, g, exit_code);
  app::add_bench(app, g, exit_code);
  app::add_record(app, g, exit_code);
  app::add_live(app, g, exit_code);
  app::add_calibrate(app, g, exit_code);
  CLI::App* train =
      app.add_subcommand("train", "Train a model from a dataset (writes a versioned model file)");
  train->require_subcommand(1);
  app::add_train_voices(*train, g, exit_code);
  app::add_train_face(*train, g, exit_code);
  app::add_train_gaze(*train, g, exit_code);
  app::add_train_speech(*train, g, exit_code);
  app::add_train_actions(*train, g, exit_code);  // cmd_actions.cpp
  app::add_train_gestures(*train, g, exit_code);
  app::add_train_expression(*train, g, exit_code);  // cmd_faces.cpp
  CLI::App* enroll = app.add_subcommand(
      "enroll", "Add known people / toys to a gallery (writes a versioned file)");
  enroll->require_subcommand(1);
  app::add_enroll_objects(*enroll, g, exit_code);
  app::add_enroll_faces(*enroll, g, exit_code);  // cmd_faces.cpp
  app.parse_complete_callback([&] {
    log::set_level(g.verbose ? log::Level::kDebug
                   : g.quiet ? log::Level::kError
                             : log::Level::kInfo);
  });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    return app::fail(std::string("internal error: ") + e.what());
  }
  return exit_code;
}
