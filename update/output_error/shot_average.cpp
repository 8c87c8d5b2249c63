// Shot averaging and the pretrigger's offset removal (shot_average.hpp).
#include "update/output_error/shot_average.hpp"

#include <cmath>
#include <utility>

#include "update/output_error/common.hpp"

namespace piezo::update::oe {

Averaged average(const OeData& d) {
  if (d.shots.empty()) fail("no shots");
  // Group by (length, pretrigger): the largest group.
  std::size_t best = 0, best_count = 0;
  for (std::size_t i = 0; i < d.shots.size(); ++i) {
    std::size_t c = 0;
    for (const auto& s : d.shots)
      c += s.v1.size() == d.shots[i].v1.size() && s.pretrigger == d.shots[i].pretrigger;
    if (c > best_count) best = i, best_count = c;
  }
  const OeShot& ref = d.shots[best];
  const std::size_t n = ref.v1.size();
  Averaged a;
  a.v1.assign(n, 0.0);
  a.v2.assign(n, 0.0);
  a.pretrigger = ref.pretrigger;
  std::vector<const OeShot*> used;
  for (const auto& s : d.shots) {
    if (s.v1.size() != n || s.pretrigger != ref.pretrigger) continue;
    if (s.v2.size() != n) fail("a shot's v1 and v2 differ in length");
    for (std::size_t i = 0; i < n; ++i) {
      if (!std::isfinite(s.v1[i]) || !std::isfinite(s.v2[i])) fail("a shot holds NaN or Inf samples");
      a.v1[i] += s.v1[i];
      a.v2[i] += s.v2[i];
    }
    used.push_back(&s);
  }
  a.shots = static_cast<int>(used.size());
  for (auto& v : a.v1) v /= a.shots;
  for (auto& v : a.v2) v /= a.shots;
  if (a.shots >= 2)
    for (const OeShot* s : used) {
      std::vector<double> d1(n), d2(n);
      for (std::size_t i = 0; i < n; ++i) {
        d1[i] = s->v1[i] - a.v1[i];
        d2[i] = s->v2[i] - a.v2[i];
      }
      a.dev1.push_back(std::move(d1));
      a.dev2.push_back(std::move(d2));
    }
  // DAQ offsets: the idle level before the drive (with a pretrigger of its own).
  if (a.pretrigger >= 16 && a.pretrigger < n) {
    double m1 = 0, m2 = 0;
    for (std::size_t i = 0; i < a.pretrigger; ++i) {
      m1 += a.v1[i];
      m2 += a.v2[i];
    }
    m1 /= double(a.pretrigger);
    m2 /= double(a.pretrigger);
    for (std::size_t i = 0; i < n; ++i) {
      a.v1[i] -= m1;
      a.v2[i] -= m2;
    }
    double s1 = 0, s2 = 0;
    for (std::size_t i = 0; i < a.pretrigger; ++i) {
      s1 += a.v1[i] * a.v1[i];
      s2 += a.v2[i] * a.v2[i];
    }
    const double p = double(a.pretrigger);
    a.with_offsets = true;
    a.offset_v[0] = m1;
    a.offset_v[1] = m2;
    a.offset_sigma_v[0] = std::sqrt(s1 / (p - 1.0) / p);
    a.offset_sigma_v[1] = std::sqrt(s2 / (p - 1.0) / p);
  }
  return a;
}

}  // namespace piezo::update::oe
