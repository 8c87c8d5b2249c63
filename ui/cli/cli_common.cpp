#include "ui/cli/cli_common.hpp"

#include <unistd.h>

#include <cstdio>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <optional>

#include "acquisition/capture.hpp"
#include "drivers/scpi_client.hpp"  // drivers::InstrumentError
#include "drivers/transport.hpp"    // drivers::TransportError
#include "dsp/impedance_files/read_any.hpp"
#include "jobs/json/json_text.hpp"
#include "jobs/pipeline/capture_fit.hpp"  // update::OeOptions, the output-error fit's options
#include "jobs/text/user_message.hpp"

namespace piezo::cli {

namespace {
void report(Context& ctx, const char* kind, const std::string& what, const nlohmann::json& extra) {
  const std::string msg = jobs::user_message(what);  // without the libraries' function names
  std::cerr << "piezobench: " << kind << ": " << msg << "\n";
  if (ctx.json) {
    nlohmann::json j = {{"error", {{"kind", kind}, {"message", msg}}}};
    for (auto& [k, v] : extra.items()) j["error"][k] = v;
    print_json(j);
  }
}
// A capture that is not HDF5 but an impedance analyzer's file (Touchstone,
// 4294A, E4990A, Bode 100, a table): says so and names the command that reads it.
std::optional<std::string> impedance_file_instead(const acq::CaptureError& e) {
  if (e.problem().rfind("not a readable HDF5 file", 0) != 0) return std::nullopt;
  try {
    const dsp::ImportedImpedance im = dsp::read_impedance_file(e.file());
    return e.file() + " is an impedance analyzer's file (" + im.format_name + ", " + std::to_string(im.size()) +
           " points), not a capture: this command needs a capture's recorded time records (.h5, written by "
           "`piezobench measure` or `demo`). For the per-mode figures of an impedance file run `piezobench "
           "figures " + e.file() + "`";
  } catch (const std::exception&) {
    return std::nullopt;  // not an impedance file either: the capture reader's message stands
  }
}

}  // namespace

int run_command(Context& ctx, const std::function<void()>& body) {
  try {
    body();
    return ctx.exit_code;
  } catch (const acq::CaptureError& e) {
    if (auto why = impedance_file_instead(e)) {
      report(ctx, "bad input", *why,
             {{"file", e.file()}, {"path", e.h5path()}, {"problem", "impedance file, not a capture"}});
      return kBadInput;
    }
    report(ctx, "bad capture", e.what(),
           {{"file", e.file()}, {"path", e.h5path()}, {"problem", e.problem()}});
    return kBadInput;
  } catch (const InputError& e) {
    report(ctx, "bad input", e.what(), nlohmann::json::object());
    return kBadInput;
  } catch (const std::invalid_argument& e) {
    report(ctx, "bad input", e.what(), nlohmann::json::object());
    return kBadInput;
  } catch (const drivers::TransportError& e) {  // an instrument that cannot be reached or stopped answering
    report(ctx, "instrument", e.what(), nlohmann::json::object());
    return kBadInput;
  } catch (const drivers::InstrumentError& e) {  // an instrument that refused a setting or answered nonsense
    report(ctx, "instrument", e.what(), nlohmann::json::object());
    return kBadInput;
  } catch (const std::exception& e) {
    report(ctx, "internal error", e.what(), nlohmann::json::object());
    return kInternal;
  }
}

// Streamed (no serialised copy in memory: a 250 000-bin spectrum is ~100 MB of text).
void print_json(const nlohmann::json& j) {
  jobs::write_json(std::cout, j);
  std::cout << std::endl;
}

double json_number(const nlohmann::json& j) {
  return j.is_number() ? j.get<double>() : std::numeric_limits<double>::quiet_NaN();
}

void add_chain_tolerance_options(CLI::App* cmd, update::OeOptions& o) {
  cmd->add_option("--r1-tolerance", o.r1_rel_sigma,
                  "Standard uncertainty of R1, a fraction (the samples cannot tell it from the constants)")
      ->check(CLI::Range(0.0, 0.5))
      ->capture_default_str();
  cmd->add_option("--cp-sigma", o.cp_sigma_f,
                  "Standard uncertainty of the capacitance across the transducer (cable, DAQ input), F")
      ->check(CLI::Range(0.0, 1e-6))
      ->capture_default_str();
  cmd->add_option("--gain-tolerance", o.gain_rel_sigma, "Standard uncertainty of the channels' gain ratio, a fraction")
      ->check(CLI::Range(0.0, 0.5))
      ->capture_default_str();
  cmd->add_option("--skew-sigma", o.skew_sigma_s, "Standard uncertainty of the channels' skew, s")
      ->check(CLI::Range(0.0, 1e-3))
      ->capture_default_str();
  // Issue 19: the damping model of the output-error fit.
  static const std::map<std::string, update::OeDamping> damping_models = {
      {"rayleigh", update::OeDamping::rayleigh}, {"complex", update::OeDamping::complex_constants}};
  cmd->add_option(
         "--damping-model", o.damping,
         "Damping model of the output-error fit: rayleigh (C = beta K) or complex (cE(1 + j/Qm), "
         "Qm fitted with its sigma)")
      ->transform(CLI::CheckedTransformer(damping_models, CLI::ignore_case))
      ->default_str(o.damping == update::OeDamping::rayleigh ? "rayleigh" : "complex");
}

void add_json_flag(CLI::App* cmd, Context& ctx) {
  cmd->add_flag("--json", ctx.json, "Machine-readable JSON output on stdout");
}

ProgressBar::ProgressBar(std::string label, bool enabled)
    : label_(std::move(label)), enabled_(enabled && ::isatty(STDERR_FILENO)) {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::update(double fraction, const std::string& detail) {
  if (!enabled_ || finished_) return;
  fraction = std::clamp(fraction, 0.0, 1.0);
  int permille = static_cast<int>(fraction * 1000);
  if (permille == last_permille_) return;
  last_permille_ = permille;
  constexpr int kWidth = 30;
  int fill = static_cast<int>(fraction * kWidth);
  std::fprintf(stderr, "\r%-12s [%s%s] %5.1f%% %s", label_.c_str(), std::string(fill, '#').c_str(),
               std::string(kWidth - fill, '.').c_str(), fraction * 100.0, detail.c_str());
  std::fflush(stderr);
}

void ProgressBar::finish() {
  if (!enabled_ || finished_) return;
  finished_ = true;
  if (last_permille_ >= 0) std::fprintf(stderr, "\n");
}

}  // namespace piezo::cli
