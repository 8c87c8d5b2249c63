// The estimator registry (estimator.hpp): the registry's checks and the one
// list of the estimators compiled in.
#include <stdexcept>

#include "acquisition/estimators/estimator.hpp"

namespace piezo::acq {

void EstimatorRegistry::add(EstimatorEntry e) {
  if (e.key.empty()) throw std::invalid_argument("EstimatorRegistry::add: empty key");
  if (find(e.key)) throw std::invalid_argument("EstimatorRegistry::add: duplicate key '" + e.key + "'");
  if (e.label.empty()) throw std::invalid_argument("EstimatorRegistry::add: '" + e.key + "' has no label");
  if (!e.estimate) throw std::invalid_argument("EstimatorRegistry::add: '" + e.key + "' has no function");
  if (!e.caps.transient_shots && !e.caps.sine_shots)
    throw std::invalid_argument("EstimatorRegistry::add: '" + e.key + "' needs neither transient nor sine shots");
  entries_.push_back(std::move(e));
}

const EstimatorEntry* EstimatorRegistry::find(const std::string& key) const {
  for (const auto& e : entries_)
    if (e.key == key) return &e;
  return nullptr;
}

const EstimatorEntry& EstimatorRegistry::at(const std::string& key) const {
  if (const auto* e = find(key)) return *e;
  throw std::invalid_argument("unknown estimator '" + key + "' (expected " + join_keys(keys()) + ")");
}

std::vector<std::string> EstimatorRegistry::keys(const std::function<bool(const EstimatorEntry&)>& keep) const {
  std::vector<std::string> out;
  for (const auto& e : entries_)
    if (!keep || keep(e)) out.push_back(e.key);
  return out;
}

std::string join_keys(const std::vector<std::string>& keys, const std::string& sep, const std::string& last) {
  std::string out;
  for (std::size_t k = 0; k < keys.size(); ++k)
    out += (k == 0 ? "" : k + 1 == keys.size() ? last : sep) + keys[k];
  return out;
}

std::string estimator_table_markdown(const EstimatorRegistry& r) {
  std::string out = "| key | label | needs | gives | what it is |\n| --- | --- | --- | --- | --- |\n";
  for (const auto& e : r.entries()) {
    const auto& c = e.caps;
    std::string needs = c.sine_shots ? "stepped-sine shots, one frequency each" : "transient shots";
    if (c.transient_shots && c.sine_shots) needs = "transient or stepped-sine shots";
    if (c.averages_shots) needs += ", averaged";
    if (c.segments) needs += ", as segments";
    std::string gives = "Z(f)";
    if (c.sigma_per_point) gives += ", σ per point (" + e.sigma_source + ")";
    if (c.modes) gives += ", modes (poles) and a model order";
    out += "| `" + e.key + "` | " + e.label + " | " + needs + " | " + gives + " | " + e.description + " |\n";
  }
  return out;
}

OwnedRecord mean_record(std::span<const dsp::DividerRecord> records) {
  if (records.empty()) throw std::invalid_argument("mean_record: no record");
  const dsp::DividerRecord& first = records.front();
  OwnedRecord avg;
  avg.v1.assign(first.v1.begin(), first.v1.end());
  avg.v2.assign(first.v2.begin(), first.v2.end());
  avg.sample_rate_hz = first.sample_rate_hz;
  avg.r1_ohm = first.r1_ohm;
  avg.pretrigger_samples = first.pretrigger_samples;
  avg.daq_range_v = first.daq_range_v;
  avg.v2_range_v = first.v2_range_v;
  for (std::size_t k = 1; k < records.size(); ++k)
    for (std::size_t i = 0; i < avg.v1.size(); ++i) {
      avg.v1[i] += records[k].v1[i];
      avg.v2[i] += records[k].v2[i];
    }
  for (std::size_t i = 0; i < avg.v1.size(); ++i) {
    avg.v1[i] /= double(records.size());
    avg.v2[i] /= double(records.size());
  }
  return avg;
}

// One line per estimator; each entry is defined in its own file of this folder.
EstimatorEntry prony_estimator();
EstimatorEntry fft_estimator();
EstimatorEntry xspec_estimator();
EstimatorEntry sine_estimator();

void register_builtin_estimators(EstimatorRegistry& r) {
  r.add(prony_estimator());
  r.add(fft_estimator());
  r.add(xspec_estimator());
  r.add(sine_estimator());
}

namespace {
EstimatorRegistry make_builtin() {
  EstimatorRegistry r;
  register_builtin_estimators(r);
  return r;
}
}  // namespace

const EstimatorRegistry& builtin_estimators() {
  static const EstimatorRegistry r = make_builtin();  // built once, never changed
  return r;
}

}  // namespace piezo::acq
