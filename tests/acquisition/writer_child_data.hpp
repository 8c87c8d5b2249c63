#pragma once
// The deterministic shots written by writer_child, so the crash test can check
// every recovered sample.
#include <cmath>

#include "acquisition/capture.hpp"

namespace piezo::test {
inline acq::Shot child_shot(int k, std::size_t n) {
  acq::Shot s;
  s.sample_rate_hz = 1e7;
  s.excitation = acq::Excitation::Arbitrary;
  s.v1.resize(n);
  s.v2.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    s.v1[i] = std::sin(1e-3 * static_cast<double>(i) + k);
    s.v2[i] = 0.5 * std::cos(2e-3 * static_cast<double>(i) - k);
  }
  return s;
}
}  // namespace piezo::test
