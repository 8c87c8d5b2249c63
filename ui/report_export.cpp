#include "ui/report_export.hpp"

#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "dsp/impedance_io.hpp"

namespace piezo::ui {

namespace {
const Curve& measured(const PipelineResult& r) {
  if (r.curves.empty()) throw std::runtime_error("export: no impedance estimate in this result");
  return r.curves.front();  // the Prony-SS estimate the update used
}

dsp::ImpedanceResult as_impedance(const Curve& c) {
  dsp::ImpedanceResult z;
  z.method = c.label;
  z.f_hz = Eigen::Map<const Eigen::VectorXd>(c.f_hz.data(), static_cast<Eigen::Index>(c.f_hz.size()));
  z.z_ohm = Eigen::Map<const Eigen::VectorXcd>(c.z_ohm.data(), static_cast<Eigen::Index>(c.z_ohm.size()));
  return z;
}

std::ofstream open_out(const std::string& path) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("export: cannot write " + path);
  return f;
}
}  // namespace

void export_csv(const PipelineResult& r, const std::string& path) {
  auto f = open_out(path);
  dsp::write_impedance_csv(f, as_impedance(measured(r)));
}

void export_touchstone(const PipelineResult& r, const std::string& path) {
  auto f = open_out(path);
  dsp::write_touchstone_s1p(f, as_impedance(measured(r)), 50.0);
}

nlohmann::json report_json(const PipelineResult& r) {
  nlohmann::json j;
  j["capture"] = r.capture_path;
  j["shots"] = r.shots;
  j["shots_averaged"] = r.shots_averaged;
  j["awg_idn"] = r.awg_idn;
  j["daq_idn"] = r.daq_idn;
  j["resonances_hz"] = r.resonances_hz;
  j["antiresonances_hz"] = r.antiresonances_hz;
  j["order"] = r.order;
  j["parameters"] = nlohmann::json::array();
  for (const auto& p : r.params) {
    nlohmann::json row = {{"name", p.name}, {"unit", p.unit}, {"original", p.original}, {"updated", p.updated}};
    if (p.truth) row["true"] = *p.truth;
    j["parameters"].push_back(row);
  }
  j["stages"] = nlohmann::json::array();
  for (const auto& s : r.stages) j["stages"].push_back({{"name", s.name}, {"ran", s.ran}, {"note", s.note}});
  j["verdict"] = r.verdict;
  j["warnings"] = r.warnings;
  return j;
}

void export_json(const PipelineResult& r, const std::string& path) {
  auto f = open_out(path);
  f << report_json(r).dump(2) << "\n";
}

}  // namespace piezo::ui
