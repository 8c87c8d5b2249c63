#pragma once
// A capture's shot as the estimators take it (dsp/ does not know capture files).
#include <algorithm>

#include "acquisition/capture.hpp"
#include "dsp/impedance_types.hpp"

namespace piezo::acq {

inline dsp::DividerRecord divider_record(const Capture& cap, const Shot& s) {
  return {s.v1, s.v2, s.sample_rate_hz, cap.setup.divider_r1_ohm,
          static_cast<std::size_t>(std::max<std::int64_t>(0, s.pretrigger_samples)), s.range_v(1),
          s.range_v(2)};
}

}  // namespace piezo::acq
