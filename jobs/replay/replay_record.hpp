#pragma once
// One replayed capture as a record of the results file and a JSON line:
//   {"path", "sha256", "status": "ok", "material", "result": <report_json>}
//   {"path", "sha256", "status": "failed", "error": {"kind", "message"}}
// The "result" object is jobs/export/report_export's report_json(), so whatever the
// pipeline reports (parameters, features, stages, diagnosis) lands here too.
// The JSON line adds "key" and "elapsed_s" (kept out of the stored JSON so
// that the same capture replayed twice stores the same text).
#include <string>

#include <nlohmann/json.hpp>

#include "acquisition/results_file.hpp"
#include "jobs/pipeline/pipeline.hpp"

namespace piezo::jobs::replay {

// The record's name in the results file: the first 32 hex digits of
// SHA-256(path "\n" sha256). Same capture at the same path → same key, on
// any machine, in any shard.
std::string record_key(const std::string& path, const std::string& sha256);

acq::ResultRecord ok_record(const std::string& path, const std::string& sha256,
                            const std::string& material, const jobs::PipelineResult& r,
                            double elapsed_s);
acq::ResultRecord failed_record(const std::string& path, const std::string& sha256,
                                const std::string& kind, const std::string& message,
                                double elapsed_s);

// The JSON object of a stored record (its result_json plus key and elapsed_s).
nlohmann::json record_json(const acq::ResultRecord& rec);

}  // namespace piezo::jobs::replay
