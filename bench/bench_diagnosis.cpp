// The one-shot gap diagnosis (issue 18; target: under 1 s): the output-error
// fit of one exp_decay shot with the catalogue's effects scanned, and the
// held-out check on its one-shot chirp — refsim corpus captures (another
// simulator's files), a control and one with a channel skew; an end mass and a
// dielectric loss, the slowest kinds.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

#include "acquisition/capture_file.hpp"
#include "jobs/pipeline/capture_fit.hpp"
#include "update/gap_diagnosis.hpp"
#include "update/gap_output_error.hpp"

namespace {

namespace fs = std::filesystem;
const fs::path kCorpus = fs::path(PIEZO_SOURCE_DIR) / ".." / "shared" / "corpus" / "refsim-v1";

void BM_OneShotDiagnosis(benchmark::State& state, const std::string& which, bool heldout) {
  const fs::path dir = kCorpus / which;
  if (!fs::exists(dir / "fit.h5")) {
    state.SkipWithError(("no corpus at " + dir.string()).c_str());
    return;
  }
  const auto cap = piezo::acq::read_capture(dir / "fit.h5");
  const auto ho_cap = piezo::acq::read_capture(dir / "holdout.h5");
  for (auto _ : state) {
    // As the pipeline does it: the tube model, the fit with its scan, the diagnosis.
    const auto cm = piezo::jobs::capture_model(cap, "apc850", true);
    piezo::jobs::CaptureFitRequest req;
    req.options.scan_effects = piezo::update::supported_gap_effects();
    const auto fit = piezo::jobs::fit_capture(cap, req, cm).result;
    if (!fit.ok()) {
      state.SkipWithError(fit.message.c_str());
      return;
    }
    piezo::update::GapDiagnosis d;
    if (heldout) {
      piezo::update::OeHeldout ho;
      ho.data = piezo::jobs::capture_oe_data(ho_cap, std::nullopt);
      ho.description = "holdout.h5";
      d = piezo::update::gap_from_output_error(fit, which, *cm.solver, cm.cls, ho, req.options);
    } else {
      d = piezo::update::gap_from_output_error(fit, which);
    }
    benchmark::DoNotOptimize(d);
    state.counters["fe_models_fit"] = fit.evaluations;
    for (const auto& e : fit.effects)
      if (e.fe_models > 0) state.counters["fe_" + e.name] = e.fe_models;
  }
}
BENCHMARK_CAPTURE(BM_OneShotDiagnosis, control_12, std::string("12"), false)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_OneShotDiagnosis, control_12_heldout, std::string("12"), true)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_OneShotDiagnosis, skew_06, std::string("06"), false)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_OneShotDiagnosis, skew_06_heldout, std::string("06"), true)->Unit(benchmark::kMillisecond)->Iterations(1);
// The slow kinds: an end mass (extra starts where the capture shows a misfit)
// and a dielectric loss (both loss laws, lack of fit left in the fit).
BENCHMARK_CAPTURE(BM_OneShotDiagnosis, mass_02_heldout, std::string("02"), true)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_OneShotDiagnosis, dielectric_14_heldout, std::string("14"), true)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
