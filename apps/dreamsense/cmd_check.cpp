// `dreamsense check SESSION [--repair OUT]`: validates a session without analysing it; with
// --repair writes a repaired copy (sources/session_check.hpp, docs/session_format.md "check").

#include "dreamsense/sources/session_check.hpp"

#include <cstdio>
#include <memory>

#include "commands.hpp"

namespace dreamsense::app {

namespace {
struct CheckFlags {
  std::string session, repair, json;
  bool force = false;
  bool follow_links = false;
};
}  // namespace

void add_check(CLI::App& app, const GlobalFlags& g, int& exit_code) {
  auto flags = std::make_shared<CheckFlags>();
  CLI::App* cmd = app.add_subcommand(
      "check",
      "Validate a session without analysing it: per-stream table of records, gaps and damage; exit "
      "0 when sound, 1 when damaged; --repair OUT writes a repaired copy");
  cmd->add_option("session", flags->session, "Session folder (with session.yaml)")->required();
  cmd->add_option("--repair", flags->repair,
                  "Write a repaired copy into this new folder: rebuilt indices, torn tails cut, "
                  "damaged records dropped; exit 0 when the copy is complete and sound");
  cmd->add_flag("--force", flags->force, "With --repair: replace the contents of a non-empty OUT")
      ->needs("--repair");
  cmd->add_option("--json", flags->json,
                  "Write the check (and repair) as JSON to FILE, or - for stdout");
  cmd->add_flag("--follow-links", flags->follow_links,
                "Follow session files that are links to files outside the session folder");
  cmd->callback([flags, &g, &exit_code] {
    sources::SessionCheckOptions co;
    co.follow_links_outside = flags->follow_links;
    if (flags->repair.empty()) {
      auto check = sources::check_session(flags->session, co);
      if (!check) {
        exit_code = fail(check.error());
        return;
      }
      if (!g.quiet) std::fputs(check->table().c_str(), stderr);
      if (auto st = write_json(flags->json, check->to_json()); !st) {
        exit_code = fail(st.error());
        return;
      }
      exit_code = check->sound() ? kExitOk : kExitFailure;
      return;
    }
    sources::SessionRepairOptions ro;
    ro.force = flags->force;
    ro.check = co;
    auto repair = sources::repair_session(flags->session, flags->repair, ro);
    if (!repair) {
      exit_code = fail(repair.error());
      return;
    }
    if (!g.quiet) {
      std::fputs(repair->before.table().c_str(), stderr);
      std::fprintf(stderr, "\nrepaired copy: %s\n", flags->repair.c_str());
      for (const auto& r : repair->streams)
        if (r.dropped + r.torn_cut + r.recovered > 0 || r.removed || r.calibration_removed)
          std::fprintf(
              stderr,
              "  %s: %llu kept, %llu damaged dropped, %llu torn cut, %llu indexed again%s%s\n",
              r.stream.c_str(), static_cast<unsigned long long>(r.kept),
              static_cast<unsigned long long>(r.dropped),
              static_cast<unsigned long long>(r.torn_cut),
              static_cast<unsigned long long>(r.recovered), r.removed ? ", stream left out" : "",
              r.calibration_removed ? ", calibration left out" : "");
      for (const auto& n : repair->notes) std::fprintf(stderr, "  note: %s\n", n.c_str());
      std::fprintf(stderr, "  the copy is %s (complete: %s)\n",
                   repair->after.sound() ? "sound" : "NOT sound",
                   repair->complete ? "true" : "false");
    }
    nlohmann::json j = repair->before.to_json();
    j["repair"] = repair->to_json();
    if (auto st = write_json(flags->json, j); !st) {
      exit_code = fail(st.error());
      return;
    }
    exit_code = repair->complete ? kExitOk : kExitFailure;
  });
}

}  // namespace dreamsense::app
