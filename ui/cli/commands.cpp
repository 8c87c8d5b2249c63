// The command registry (commands.hpp) and the one list of the commands.
#include "ui/cli/commands.hpp"

#include <stdexcept>

namespace piezo::cli {

void CommandRegistry::add(CommandEntry e) {
  if (e.name.empty()) throw std::invalid_argument("CommandRegistry::add: empty name");
  for (const auto& x : entries_)
    if (x.name == e.name) throw std::invalid_argument("CommandRegistry::add: duplicate command '" + e.name + "'");
  if (e.summary.empty()) throw std::invalid_argument("CommandRegistry::add: '" + e.name + "' has no summary");
  if (!e.add) throw std::invalid_argument("CommandRegistry::add: '" + e.name + "' has no function");
  entries_.push_back(std::move(e));
}

void register_builtin_commands(CommandRegistry& r) {
  r.add({"demo", "the main job, end to end, on the simulated bench", register_demo_command});
  r.add({"measure", "acquires a capture on a bench: simulated, SCPI over TCP, USBTMC, a Comedi board",
         register_measure_command});
  r.add({"capture", "`capture info`: a capture's set-up and, per shot: N, rate, excitation, min/max/RMS, clipping",
         register_capture_command});
  r.add({"impedance",
         "Z(f) of a capture by Prony-SS, FFT ratio, cross spectra or stepped sine; compensation, uncertainty, "
         "CSV/Touchstone",
         register_impedance_command});
  r.add({"update", "the constants straight from a capture, or from impedance features (extended CMCM, LM)",
         register_update_command});
  r.add({"diagnose", "the sim-to-real gap of a capture, checked on held-out data", register_diagnose_command});
  r.add({"figures",
         "per-mode figures with σ (fs, fp, fm, fn, fr, fa, k_eff two ways, Qm two ways, R1 L1 C1) from a capture or "
         "any impedance analyzer's file (HIOKI, E4990A, 4294A, LabOne, Bode 100, Touchstone s1p/s2p, tables with "
         "`--columns`); each mode `ok` or `unreliable` with the reasons, the fit `ok` or `inadequate`",
         register_figures_command});
  r.add({"replay",
         "headless replay of recorded captures, one or thousands: results, reports, pass/fail, the lot report",
         register_replay_command});
  r.add({"replay-merge", "merges the results files of sharded replays", register_replay_merge_command});
  r.add({"model",
         "the FE model: `materials`, `modal`, `impedance`, `sensitivity`, `mode-shape-cmcm`, "
         "`three-d` (the 3-D tube by circumferential harmonics), `constrained` (Fig 19), `bar` (Appendix A's "
         "33- and 31-mode bar vibrators), `charge` (§5.1: |Z| from the tube's charge, Figs 24-29)",
         register_model_command});
  r.add({"instruments", "the driver families: roles, how each is chosen, its simulated twin",
         register_instruments_command});
  r.add({"sim-instrument", "serves the simulated bench over TCP, so the real transport and drivers run",
         register_sim_instrument_command});
}

const CommandRegistry& builtin_commands() {
  static CommandRegistry r;
  static const bool filled = (register_builtin_commands(r), true);  // once, before the first use
  (void)filled;
  return r;
}

void add_commands(CLI::App& app, Context& ctx, const CommandRegistry& r) {
  for (const auto& e : r.entries()) {
    e.add(app, ctx);
    try {
      app.get_subcommand(e.name);
    } catch (const CLI::OptionNotFound&) {
      throw std::logic_error("command registry: '" + e.name + "' added no subcommand of that name");
    }
  }
}

std::string command_table_markdown(const CommandRegistry& r) {
  std::string out = "| command | what it does |\n| --- | --- |\n";
  for (const auto& e : r.entries()) out += "| `" + e.name + "` | " + e.summary + " |\n";
  return out;
}

}  // namespace piezo::cli
