// What the tests of the output-error fit's pieces start from: the bench tube
// (the default geometry), its FE solver, the isotropic material class with
// APC 850's nominal constants, a bench's data, and a decaying record on two
// channels.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <random>

#include "model/material_presets.hpp"
#include "model/material_spec.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"
#include "update/output_error/forward_model.hpp"

namespace piezo::test {

class OeTestTube : public ::testing::Test {
 protected:
  model::TubeModel tube{model::TubeGeometry{}};
  model::ModalSolver solver{tube};
  update::MaterialClass cls = update::MaterialClass::isotropic();
  update::TubeParams nominal = model::isotropic_params(model::resolve_material({"apc850", true, ""}).d);
  // A record's bench: the sample rate and the divider's R1 (3140 Ω).
  static update::OeData bench_data(double fs) {
    update::OeData d;
    d.sample_rate_hz = fs;
    d.circuit.r1_ohm = 3140.0;
    return d;
  }
  // The fit's coordinates about the nominal constants (Rayleigh β0 = 1e-7).
  update::oe::Coordinates5 nominal_coordinates() const { return {nominal, 1e-7, update::OeDamping::rayleigh}; }
};

// v1 = e^(−3000 t) and v2 = v1/2, each with its own white noise of `noise`
// volts (so v2's total is √1.25 times v1's), n samples at fs.
inline update::oe::Averaged decaying_record(std::size_t n, double fs, unsigned seed, double noise) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01;
  update::oe::Averaged rec;
  rec.v1.resize(n);
  rec.v2.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    rec.v1[i] = std::exp(-3000.0 * double(i) / fs) + noise * n01(rng);
    rec.v2[i] = 0.5 * rec.v1[i] + noise * n01(rng);
  }
  rec.shots = 1;
  return rec;
}

}  // namespace piezo::test
