#pragma once
// Shared conventions of the `piezobench` commands: exit codes, --json output,
// error reporting. Every command registers itself through a register_* function,
// listed in the command registry (ui/cli/commands.hpp).
// The CLI's room (ui/cli): commands parse options, call a job (jobs/) and print.
#include <CLI/CLI.hpp>
#include <cstddef>
#include <functional>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>

#include "jobs/job_error.hpp"

namespace piezo::update {
struct OeOptions;
}
namespace piezo::jobs {
struct ModelRequest;
}

namespace piezo::cli {

enum ExitCode : int { kOk = 0, kInternal = 1, kBadInput = 2 };

// Error whose cause is the user's input (bad file, bad option value): exit 2.
// The jobs throw the same type (jobs/job_error.hpp).
using InputError = jobs::InputError;

struct Context {
  bool json = false;  // --json: machine-readable output on stdout
  int exit_code = kOk;
};

// Runs `body`, mapping exceptions to exit codes and messages (stderr, and a
// {"error": ...} object on stdout when --json is set).
int run_command(Context& ctx, const std::function<void()>& body);

void print_json(const nlohmann::json& j);

// A JSON number as a double; NaN for null (a value JSON cannot hold) or anything else.
double json_number(const nlohmann::json& j);

// Every command takes --json (also accepted before the command name).
void add_json_flag(CLI::App* cmd, Context& ctx);
// The measurement chain's tolerances that the output-error fit carries into
// every sigma (update::OeOptions): --r1-tolerance, --cp-sigma,
// --gain-tolerance, --skew-sigma, defaults as OeOptions states them; and its
// damping model, --damping-model rayleigh|complex (OeOptions::damping).
void add_chain_tolerance_options(CLI::App* cmd, update::OeOptions& o);

// Text progress bar on stderr (only when stderr is a terminal or forced).
class ProgressBar {
 public:
  explicit ProgressBar(std::string label, bool enabled = true);
  ~ProgressBar();
  void update(double fraction, const std::string& detail = {});
  void finish();

 private:
  std::string label_;
  bool enabled_;
  bool finished_ = false;
  int last_permille_ = -1;
};

// `replay --jobs` by default: the number of cores (std::thread::hardware_concurrency,
// at least 1, at most 256).
std::size_t default_jobs();

// The commands' register functions: each adds its one top-level command to
// `app`; ui/cli/commands.cpp lists them (the command registry).
void register_capture_command(CLI::App& app, Context& ctx);
void register_demo_command(CLI::App& app, Context& ctx);
void register_measure_command(CLI::App& app, Context& ctx);
void register_sim_instrument_command(CLI::App& app, Context& ctx);
void register_instruments_command(CLI::App& app, Context& ctx);
void register_model_command(CLI::App& app, Context& ctx);
// `model mode-shape-cmcm` (cmd_model_mode_shape.cpp), under the `model` command.
void register_mode_shape_command(CLI::App* model, Context& ctx);
// `model three-d` and `model constrained` (cmd_model_3d.cpp), under `model`;
// `add_model_options` adds the tube's options (--material, --nr, …).
void register_model_3d_commands(CLI::App* model, Context& ctx,
                                const std::function<void(CLI::App*, jobs::ModelRequest&)>& add_model_options);
// `model bar` (cmd_model_bar.cpp), under `model`: the seed's Appendix A.
void register_model_bar_command(CLI::App* model, Context& ctx);
// `model charge` (cmd_model_charge.cpp), under `model`: the seed's §5.1 study (Figs 24–29).
void register_model_charge_command(CLI::App* model, Context& ctx,
                                   const std::function<void(CLI::App*, jobs::ModelRequest&)>& add_model_options);
void register_impedance_command(CLI::App& app, Context& ctx);
void register_update_command(CLI::App& app, Context& ctx);
void register_replay_command(CLI::App& app, Context& ctx);
void register_replay_merge_command(CLI::App& app, Context& ctx);
void register_diagnose_command(CLI::App& app, Context& ctx);
void register_figures_command(CLI::App& app, Context& ctx);

}  // namespace piezo::cli
