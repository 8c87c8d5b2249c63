// The command registry (ui/cli/commands.hpp): its checks, the CLI built from
// it (every entry a subcommand, nothing else), the impedance and figures
// commands' --method choices equal to the estimator registry's keys, and the
// README's command table equal to the registry's.
#include <gtest/gtest.h>

#include <set>

#include "acquisition/estimators/estimator.hpp"
#include "tests/support/doc_table.hpp"
#include "ui/cli/commands.hpp"

using namespace piezo;
using namespace piezo::cli;

namespace {

CommandEntry entry(const std::string& name) {
  return {name, "summary", [name](CLI::App& app, Context&) { app.add_subcommand(name, "x"); }};
}

// Parses ARGS with the CLI built from the registry; true if CLI11 accepts them
// (the command's own run may still fail: its exit code is not looked at).
bool parses(std::vector<std::string> args) {
  CLI::App app{"t", "piezobench"};
  Context ctx;
  add_commands(app, ctx);
  std::reverse(args.begin(), args.end());  // CLI11 takes them last first
  try {
    app.parse(args);
  } catch (const CLI::ValidationError&) {
    return false;
  }
  return true;
}

}  // namespace

TEST(CommandRegistry, RejectsDuplicateEmptyAndIncompleteEntries) {
  CommandRegistry r;
  r.add(entry("a"));
  const std::vector<std::function<void(CommandEntry&)>> spoil = {
      [](CommandEntry&) {},                          // "a" again: a duplicate
      [](CommandEntry& e) { e.name.clear(); },      // no name
      [](CommandEntry& e) { e.summary.clear(); },   // no summary
      [](CommandEntry& e) { e.add = nullptr; }};    // no function
  for (std::size_t k = 0; k < spoil.size(); ++k) {
    CommandEntry e = entry(k == 0 ? "a" : "fresh");
    spoil[k](e);
    EXPECT_THROW(r.add(e), std::invalid_argument) << k;
  }
  ASSERT_EQ(r.entries().size(), 1u);
}

TEST(CommandRegistry, AnEntryMustAddItsOwnSubcommand) {
  CommandRegistry r;
  r.add({"named", "s", [](CLI::App& app, Context&) { app.add_subcommand("other", "x"); }});
  CLI::App app;
  Context ctx;
  EXPECT_THROW(add_commands(app, ctx, r), std::logic_error);
}

TEST(CommandRegistry, TheCliHasExactlyTheRegisteredCommands) {
  CLI::App app{"t", "piezobench"};
  Context ctx;
  add_commands(app, ctx);
  std::vector<std::string> got, want;
  for (const auto* c : app.get_subcommands({})) got.push_back(c->get_name());
  for (const auto& e : builtin_commands().entries()) want.push_back(e.name);
  EXPECT_EQ(got, want);
  EXPECT_EQ(want.size(), 12u);  // scripts call these names: none may go
  for (const char* name : {"demo", "measure", "capture", "impedance", "update", "diagnose", "figures", "replay",
                           "replay-merge", "model", "instruments", "sim-instrument"})
    EXPECT_NE(std::find(want.begin(), want.end(), name), want.end()) << name;
}

TEST(CommandRegistry, MethodChoicesAreTheEstimatorRegistrysKeys) {
  for (const auto& key : acq::builtin_estimators().keys())
    EXPECT_TRUE(parses({"impedance", "no-such.h5", "--method", key})) << key;
  EXPECT_FALSE(parses({"impedance", "no-such.h5", "--method", "bogus"}));
  EXPECT_TRUE(parses({"figures", "no-such.h5", "--method", "oe"}));
  for (const auto& e : acq::builtin_estimators().entries())
    EXPECT_EQ(parses({"figures", "no-such.h5", "--method", e.key}), e.caps.transient_shots) << e.key;
  EXPECT_FALSE(parses({"figures", "no-such.h5", "--method", "bogus"}));
}

// The README's command table is the registry's.
TEST(CommandRegistry, ReadmeTableIsTheRegistrys) {
  const std::string table = command_table_markdown();
  EXPECT_EQ(test::doc_table("README.md", table.substr(0, table.find('\n'))), table)
      << "update README.md's command table to:\n" << table;
}
