#include "jobs/report/lot_summary.hpp"

#include <algorithm>
#include <cmath>

namespace piezo::jobs::report {

Capability capability(const Limit& l, double mean, double sd, std::size_t n) {
  Capability c;
  c.one_sided = !l.two_sided();
  if (!l.numeric() || n < 2 || !(sd > 0) || !std::isfinite(sd)) return c;
  if (l.max) c.cpu = (*l.max - mean) / (3 * sd);
  if (l.min) c.cpl = (mean - *l.min) / (3 * sd);
  if (c.cpu && c.cpl) {
    c.cpk = std::min(*c.cpu, *c.cpl);
    c.cp = (*l.max - *l.min) / (6 * sd);
  } else {
    c.cpk = c.cpu ? c.cpu : c.cpl;
  }
  return c;
}

int default_bins(std::size_t n) {
  return std::clamp(static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n)))), 5, 30);
}

Histogram histogram(const std::vector<double>& v, double lo, double hi, int bins) {
  Histogram h;
  if (bins < 1) bins = 1;
  if (!(hi > lo)) {  // one value (or none): a bin around it
    const double d = lo == 0 ? 1.0 : 0.05 * std::abs(lo);
    lo -= d;
    hi += d;
  }
  h.lo = lo;
  h.hi = hi;
  h.counts.assign(static_cast<std::size_t>(bins), 0);
  for (double x : v) {
    if (!std::isfinite(x) || x < lo || x > hi) continue;
    auto k = static_cast<std::size_t>(std::floor((x - lo) / (hi - lo) * bins));
    h.counts[std::min(k, h.counts.size() - 1)]++;
  }
  return h;
}

LotSummary summarize_lot(const Limits& L, std::vector<LotRecord> records) {
  std::sort(records.begin(), records.end(), [](const LotRecord& a, const LotRecord& b) {
    return a.path != b.path ? a.path < b.path : a.key < b.key;
  });
  LotSummary s;
  s.limits_file = L.source;
  s.name = L.name;
  for (const auto& r : records) {
    s.captures.push_back({r.path, r.key, evaluate_record(L, r.record)});
    const auto& st = s.captures.back().verdict.status;
    (st == "pass" ? s.pass : st == "fail" ? s.fail : s.error)++;
  }
  for (std::size_t k = 0; k < L.limits.size(); ++k) {
    const Limit& lim = L.limits[k];
    QuantitySummary q;
    q.limit = k;
    std::vector<double> v;
    for (std::size_t i = 0; i < s.captures.size(); ++i) {
      const auto& vd = s.captures[i].verdict;
      if (vd.status == "error") continue;
      const LimitCheck& c = vd.checks[k];
      if (c.state == "not measured") {
        ++q.not_measured;
        continue;
      }
      q.below += c.state == "below min";
      q.above += c.state == "above max";
      q.not_allowed += c.state == "not allowed";
      if (lim.numeric()) {
        const double x = c.value.get<double>();
        q.values.emplace_back(i, x);
        v.push_back(x);
      } else {
        q.categories[c.value.is_string() ? c.value.get<std::string>() : c.value.dump()]++;
      }
    }
    q.n = lim.numeric() ? v.size() : q.n;
    if (!lim.numeric()) {
      for (const auto& [_, c] : q.categories) q.n += c;
    } else if (!v.empty()) {
      double sum = 0;
      for (double x : v) sum += x;
      q.mean = sum / static_cast<double>(v.size());
      double ss = 0;
      for (double x : v) ss += (x - q.mean) * (x - q.mean);
      q.sd = v.size() > 1 ? std::sqrt(ss / static_cast<double>(v.size() - 1)) : 0.0;
      q.min = *std::min_element(v.begin(), v.end());
      q.max = *std::max_element(v.begin(), v.end());
      q.robust = robust_stats(v);
      for (const auto& [i, x] : q.values)
        if (q.robust.n >= kMinForOutliers && std::abs(modified_z(x, q.robust)) > L.outlier_z)
          q.outliers.push_back(i);
      // The histogram spans the data and the limits, so both show on one axis.
      double lo = q.min, hi = q.max;
      if (lim.min) lo = std::min(lo, *lim.min);
      if (lim.max) hi = std::max(hi, *lim.max);
      const double pad = 0.02 * (hi - lo);
      q.histogram = histogram(v, lo - pad, hi + pad, L.bins.value_or(default_bins(v.size())));
      q.capability = capability(lim, q.mean, q.sd, v.size());
    }
    s.quantities.push_back(std::move(q));
  }
  return s;
}

namespace {
nlohmann::json opt(const std::optional<double>& v) {
  return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}
}  // namespace

nlohmann::json lot_json(const Limits& L, const LotSummary& s) {
  nlohmann::json j = {{"limits_file", s.limits_file},
                      {"name", s.name},
                      {"captures", s.captures.size()},
                      {"pass", s.pass},
                      {"fail", s.fail},
                      {"error", s.error},
                      {"outlier_z", L.outlier_z}};
  j["quantities"] = nlohmann::json::array();
  for (const auto& q : s.quantities) {
    const Limit& lim = L.limits[q.limit];
    nlohmann::json qj = {{"quantity", lim.quantity},
                         {"label", lim.label},
                         {"unit", lim.unit},
                         {"n", q.n},
                         {"not_measured", q.not_measured}};
    if (lim.numeric()) {
      qj["min_limit"] = opt(lim.min);
      qj["max_limit"] = opt(lim.max);
      qj["below_min"] = q.below;
      qj["above_max"] = q.above;
      qj["mean"] = q.mean;
      qj["sd"] = q.sd;
      qj["min"] = q.min;
      qj["max"] = q.max;
      qj["median"] = q.robust.median;
      qj["mad"] = q.robust.mad;
      qj["histogram"] = {
          {"lo", q.histogram.lo}, {"hi", q.histogram.hi}, {"counts", q.histogram.counts}};
      qj["outliers"] = nlohmann::json::array();
      for (std::size_t i : q.outliers) {
        const auto it = std::find_if(q.values.begin(), q.values.end(),
                                     [&](const auto& p) { return p.first == i; });
        qj["outliers"].push_back({{"path", s.captures[i].path},
                                  {"value", it->second},
                                  {"modified_z", modified_z(it->second, q.robust)}});
      }
      qj["cp"] = opt(q.capability.cp);
      qj["cpk"] = opt(q.capability.cpk);
      qj["cpu"] = opt(q.capability.cpu);
      qj["cpl"] = opt(q.capability.cpl);
      qj["one_sided"] = q.capability.one_sided;
    } else {
      qj["allowed"] = lim.allowed;
      qj["not_allowed"] = q.not_allowed;
      qj["values"] = nlohmann::json::object();
      for (const auto& [k, c] : q.categories) qj["values"][k] = c;
    }
    j["quantities"].push_back(std::move(qj));
  }
  j["failures"] = nlohmann::json::array();
  for (const auto& c : s.captures)
    if (c.verdict.status != "pass")
      j["failures"].push_back(
          {{"path", c.path}, {"status", c.verdict.status}, {"reasons", c.verdict.reasons}});
  return j;
}

}  // namespace piezo::jobs::report
