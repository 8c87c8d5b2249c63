#include "jobs/replay/replay_record.hpp"

#include "jobs/replay/sha256.hpp"
#include "jobs/export/report_export.hpp"
#include "jobs/json/json_text.hpp"

namespace piezo::jobs::replay {

std::string record_key(const std::string& path, const std::string& sha256) {
  return sha256_bytes(path + "\n" + sha256).substr(0, 32);
}

acq::ResultRecord ok_record(const std::string& path, const std::string& sha256,
                            const std::string& material, const jobs::PipelineResult& r,
                            double elapsed_s) {
  acq::ResultRecord rec;
  rec.key = record_key(path, sha256);
  rec.input_path = path;
  rec.sha256 = sha256;
  rec.status = "ok";
  rec.elapsed_s = elapsed_s;
  nlohmann::json j = {{"path", path}, {"sha256", sha256}, {"status", "ok"}, {"material", material}};
  j["result"] = jobs::report_json(r);
  rec.result_json = jobs::json_text(j);
  for (const auto& c : r.curves) rec.curves.push_back({c.label, c.f_hz, c.z_ohm});
  return rec;
}

acq::ResultRecord failed_record(const std::string& path, const std::string& sha256,
                                const std::string& kind, const std::string& message,
                                double elapsed_s) {
  acq::ResultRecord rec;
  rec.key = record_key(path, sha256);
  rec.input_path = path;
  rec.sha256 = sha256;
  rec.status = "failed";
  rec.elapsed_s = elapsed_s;
  nlohmann::json j = {{"path", path}, {"sha256", sha256}, {"status", "failed"}};
  j["error"] = {{"kind", kind}, {"message", message}};
  rec.result_json = jobs::json_text(j);
  return rec;
}

nlohmann::json record_json(const acq::ResultRecord& rec) {
  nlohmann::json j = nlohmann::json::parse(rec.result_json, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object())
    j = {{"path", rec.input_path},
         {"sha256", rec.sha256},
         {"status", "failed"},
         {"error",
          {{"kind", "bad record"}, {"message", "stored result_json is not a JSON object"}}}};
  j["key"] = rec.key;
  j["elapsed_s"] = rec.elapsed_s;
  return j;
}

}  // namespace piezo::jobs::replay
