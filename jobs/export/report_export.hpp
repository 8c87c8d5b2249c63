#pragma once
// Exports of a pipeline result: the measured impedance as CSV (f_hz,re_ohm,im_ohm)
// and Touchstone 1-port (.s1p, Z format), and a JSON report (parameters,
// features, stages, warnings). Used by the GUI's Export buttons and by headless
// replay (one JSON line per capture, and the results file).
#include <nlohmann/json.hpp>
#include <string>

#include "jobs/pipeline/pipeline.hpp"

namespace piezo::jobs {

// Each throws std::runtime_error naming the file when it cannot be written.
void export_csv(const PipelineResult& r, const std::string& path);
void export_touchstone(const PipelineResult& r, const std::string& path);
void export_json(const PipelineResult& r, const std::string& path);

// The gap diagnosis as JSON (the "diagnosis" object of the report and of `demo --json`).
nlohmann::json diagnosis_json(const update::GapDiagnosis& d);

// The JSON report that export_json writes, as a value: every scalar field of
// the result (curves excluded). A field added to PipelineResult is added here.
nlohmann::json report_json(const PipelineResult& r);

}  // namespace piezo::jobs
