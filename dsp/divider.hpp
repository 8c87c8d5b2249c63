#pragma once
// Shared front end of the estimators: checks a DividerRecord, cuts the pretrigger
// (sample `pretrigger_samples` is t = 0), removes the DAQ offset measured over
// the pretrigger, refuses clipped channels, and forms the current (v1 − v2)/R1.
#include <Eigen/Core>
#include <cstddef>

#include "dsp/impedance_types.hpp"

namespace piezo::dsp {

struct DividerSignals {
  Eigen::VectorXd v1, v2, i;  // from t = 0
  double sample_rate_hz = 0, r1_ohm = 0;
  Eigen::Index size() const { return v1.size(); }
};

struct DividerPrep {
  std::size_t max_samples = 0;         // keep only the first N samples from t = 0 (0: all)
  bool remove_pretrigger_offset = true;  // needs >= 16 pretrigger samples, else no-op
  bool refuse_clipped = true;
  std::size_t min_samples = 16;
};

// Throws std::invalid_argument naming `who` for any violated precondition.
DividerSignals prepare_divider(const DividerRecord& rec, const char* who, const DividerPrep& prep = {});



// v[k] ← v[k] − v[k−1] (v[−1] = 0: the record starts at rest at t = 0) on v1, v2, i.
void difference_in_place(DividerSignals& s);

}  // namespace piezo::dsp
