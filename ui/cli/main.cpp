// piezobench — command-line front end. Each command lives in its own cmd_*.cpp
// and is listed once, in the command registry (commands.cpp).
// Exit codes: 0 success, 2 bad input, 1 internal failure.
#include <iostream>

#include "ui/allocator_policy.hpp"
#include "ui/cli/cli_common.hpp"
#include "ui/cli/commands.hpp"
#include "ui/cli/suggest.hpp"
#include "ui/version.hpp"

int main(int argc, char** argv) {
  piezo::ui::set_allocator_policy();
  using namespace piezo::cli;
  CLI::App app{"piezobench — impedance measurement and FE model updating of piezoelectric tubes",
               "piezobench"};
  app.set_version_flag("--version", std::string("piezobench ") + piezo::kVersion);
  app.require_subcommand(1);
  Context ctx;
  app.add_flag("--json", ctx.json, "Machine-readable JSON output on stdout")->trigger_on_parse();
  add_commands(app, ctx);
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    std::cerr << did_you_mean(app);  // the nearest command or option to a mistyped one
    return kBadInput;
  }
  return ctx.exit_code;
}
