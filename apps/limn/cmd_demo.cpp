// limn demo: the whole workflow on built-in shapes, writing images and a report. The work runs in
// the GL module (demo_run.cpp).
#include "gl_commands.hpp"

namespace limn::cli {

void add_demo(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("demo", "Run the limn workflow on built-in shapes and write a report");
  auto o = std::make_shared<DemoJob>();
  cmd->add_option("-o,--output", o->dir, "Output folder (created if missing)");
  cmd->add_flag("--quick", o->quick, "Use the small variants of the 800k-quad shapes");
  cmd->add_flag("--json", o->json, "Print the report as one JSON object too");
  cmd->callback([o] { reinterpret_cast<DemoEntry>(gl_entry(kDemoEntry))(*o); });
}

}  // namespace limn::cli
