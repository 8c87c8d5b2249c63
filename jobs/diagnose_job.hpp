#pragma once
// The jobs' room (jobs/): `piezobench diagnose FIT.h5 [--holdout OTHER.h5]` —
// the sim-to-real gap of a recorded capture (issue 7). Checks the files, the
// candidates and the plot's size and folder first; replays FIT.h5 through the
// pipeline (jobs/pipeline/pipeline.hpp: estimate Z, update the model) and
// diagnoses what the updated model still misses, judged on OTHER.h5 or on
// other shots of FIT.h5; writes the PNG (jobs/report/diagnosis_plot.hpp) and
// the JSON. ui/cli/cmd_diagnose.cpp parses the options and prints.
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "jobs/pipeline/pipeline.hpp"

namespace piezo::jobs {

struct DiagnoseRequest {
  std::string fit, holdout, material, plot, plot_size = "1200x800";
  std::vector<std::string> candidates;  // empty: every effect the diagnosis can fit
  bool transverse = false;              // transversely isotropic class instead of isotropic
  // The seed's chain (extended CMCM on Prony's features) beside the output-error
  // fit: off by default as in replay (run anyway when that fit fails); on, the
  // parameters carry "cmcm" beside the update (`diagnose --seed-chain`).
  bool seed_chain = false;
  update::OeOptions oe;
  // How the nominal material was chosen when it was a guess (said at once).
  std::function<void(const std::string&)> warn;
  std::function<void(const PipelineProgress&)> progress;
};

struct DiagnoseResult {
  std::string material;     // the nominal material used
  PipelineResult pipeline;  // its diagnosis is set
  std::string plot;         // the PNG written, or empty
};

// Throws InputError for a missing or invalid file, too few dut shots, a bad
// candidate or plot size, a diagnosis that could not run (each named with
// its file).
DiagnoseResult run_diagnose(const DiagnoseRequest& req);

// The diagnosis (jobs/export/report_export.hpp's diagnosis_json) with the
// context: capture, holdout_capture, material, material_class, shots,
// parameters, stages, plot, warnings.
nlohmann::json diagnose_json(const DiagnoseRequest& req, const DiagnoseResult& r);

}  // namespace piezo::jobs
