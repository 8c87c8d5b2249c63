#pragma once
// The record the output-error fit works on: a capture's shots of equal length
// and pretrigger averaged, each shot's deviation from the average kept (for
// the noise estimate, noise.hpp), and the DAQ offsets removed with the
// pretrigger's mean. Internal to update/output_error/.
#include <cstddef>
#include <vector>

#include "update/output_error.hpp"

namespace piezo::update::oe {

// A shot more than this late or early against the first (samples) has the
// shots aligned before they are averaged.
inline constexpr double kJitterSamples = 0.1;

// Shots averaged per (length, pretrigger) group; the largest group is used.
struct Averaged {
  std::vector<double> v1, v2;
  std::size_t pretrigger = 0;
  std::vector<std::vector<double>> dev1, dev2;  // each shot minus the average (K ≥ 2)
  int shots = 0;
  // Per used shot: its index among OeData::shots.
  std::vector<int> index;
  // Trigger jitter: each used shot's delay against the first (samples; the
  // first's is 0), and whether the shots were aligned before averaging.
  std::vector<double> jitter_samples;
  bool aligned = false;
  // The pretrigger's means removed from each channel (with_offsets: a
  // pretrigger of 16 samples or more), and their standard errors.
  bool with_offsets = false;
  double offset_v[2] = {0, 0}, offset_sigma_v[2] = {0, 0};
};

// Throws std::invalid_argument (fail) for no shots, v1 and v2 of different
// lengths, or non-finite samples.
Averaged average(const OeData& d);

}  // namespace piezo::update::oe
