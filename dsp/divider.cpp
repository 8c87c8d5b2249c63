#include "dsp/divider.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "dsp/signal_stats.hpp"

namespace piezo::dsp {

DividerSignals prepare_divider(const DividerRecord& rec, const char* who, const DividerPrep& prep) {
  auto fail = [who](const std::string& m) { throw std::invalid_argument(std::string(who) + ": " + m); };
  if (rec.v1.size() != rec.v2.size())
    fail("v1 and v2 differ in length (" + std::to_string(rec.v1.size()) + " vs " +
         std::to_string(rec.v2.size()) + ")");
  if (!(rec.sample_rate_hz > 0.0) || !std::isfinite(rec.sample_rate_hz)) fail("sample rate must be positive");
  if (!(rec.r1_ohm > 0.0) || !std::isfinite(rec.r1_ohm)) fail("R1 must be positive");
  const std::size_t n = rec.v1.size();
  if (rec.pretrigger_samples >= n) fail("pretrigger covers the whole record");
  std::size_t avail = n - rec.pretrigger_samples;
  const std::size_t use = prep.max_samples ? std::min(prep.max_samples, avail) : avail;
  if (prep.max_samples && prep.max_samples > avail)
    fail("asked for " + std::to_string(prep.max_samples) + " samples after t = 0, the record has " +
         std::to_string(avail));
  if (use < prep.min_samples)
    fail("too short: " + std::to_string(use) + " samples after t = 0, need at least " +
         std::to_string(prep.min_samples));
  for (std::size_t k = 0; k < n; ++k)
    if (!std::isfinite(rec.v1[k]) || !std::isfinite(rec.v2[k])) fail("signals contain NaN or Inf");
  DividerSignals s;
  s.sample_rate_hz = rec.sample_rate_hz;
  s.r1_ohm = rec.r1_ohm;
  const auto p0 = static_cast<Eigen::Index>(rec.pretrigger_samples);
  const auto u = static_cast<Eigen::Index>(use);
  Eigen::Map<const Eigen::VectorXd> m1(rec.v1.data(), static_cast<Eigen::Index>(n));
  Eigen::Map<const Eigen::VectorXd> m2(rec.v2.data(), static_cast<Eigen::Index>(n));
  s.v1 = m1.segment(p0, u);
  s.v2 = m2.segment(p0, u);
  if (prep.remove_pretrigger_offset && p0 >= 16) {
    s.v1.array() -= m1.head(p0).mean();
    s.v2.array() -= m2.head(p0).mean();
  }
  // A constant channel holds no response: say so before the clip heuristic
  // (which would read a constant as a converter pinned at full scale).
  for (const auto* v : {&s.v1, &s.v2})
    if (!(v->maxCoeff() - v->minCoeff() > 1e-12 * v->cwiseAbs().maxCoeff()))
      fail(std::string(v == &s.v1 ? "v1" : "v2") + " is constant after t = 0: no response to analyse");
  if (prep.refuse_clipped) {  // over the analysed span: the pretrigger may sit flat at an offset
    ClipDetection clip;
    clip.range_v = rec.range_v(1);
    if (compute_stats(rec.v1.subspan(rec.pretrigger_samples, use), clip).clipped)
      fail("v1 is clipped (samples at the converter limit)");
    clip.range_v = rec.range_v(2);
    if (compute_stats(rec.v2.subspan(rec.pretrigger_samples, use), clip).clipped)
      fail("v2 is clipped (samples at the converter limit)");
  }
  s.i = (s.v1 - s.v2) / rec.r1_ohm;
  return s;
}

void difference_in_place(DividerSignals& s) {
  for (Eigen::VectorXd* v : {&s.v1, &s.v2, &s.i})
    for (Eigen::Index k = v->size() - 1; k > 0; --k) (*v)[k] -= (*v)[k - 1];
}

}  // namespace piezo::dsp
