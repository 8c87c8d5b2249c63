#pragma once
// The command registry (after libscopehal's AddDriverClass): one entry per
// top-level command of `piezobench` — its name as typed, a one-line summary
// (the README's command table, checked against this list by
// tests/cli/test_cli_commands.cpp) and the function that adds it with its
// options. main() adds every entry in order; nothing else lists the commands.
// How to add a command: docs/extending.md.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

#include "ui/cli/cli_common.hpp"

namespace piezo::cli {

struct CommandEntry {
  std::string name;     // "impedance": the subcommand as typed
  std::string summary;  // one line, Markdown: the README's "what it does"
  std::function<void(CLI::App&, Context&)> add;  // adds the subcommand `name` to the app
};

class CommandRegistry {
 public:
  // Throws std::invalid_argument on an empty or duplicate name, an empty summary or a missing function.
  void add(CommandEntry e);
  const std::vector<CommandEntry>& entries() const { return entries_; }

 private:
  std::vector<CommandEntry> entries_;
};

// Every command, in the order `piezobench --help` and the README list them:
// the main job's order, then the model and the instruments.
void register_builtin_commands(CommandRegistry& r);
const CommandRegistry& builtin_commands();

// Adds every entry's command to `app`; throws std::logic_error when an entry's
// function did not add a subcommand of its name.
void add_commands(CLI::App& app, Context& ctx, const CommandRegistry& r = builtin_commands());

// The README's table: "| command | what it does |", its rule, one row per entry.
std::string command_table_markdown(const CommandRegistry& r = builtin_commands());

}  // namespace piezo::cli
