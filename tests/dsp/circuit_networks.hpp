#pragma once
// Networks with known elements for the equivalent-circuit tests
// (test_equivalent_circuit.cpp, test_circuit_adequacy.cpp).
#include <cmath>

#include "dsp/equivalent_circuit.hpp"

namespace piezo::dsp::test_networks {

inline constexpr double kTwoPi = 2.0 * M_PI;

// A branch with resonance fs, quality q and motional capacitance c.
inline CircuitBranch branch(double fs, double q, double c) {
  CircuitBranch b;
  b.c_f = c;
  b.l_h = 1.0 / (std::pow(kTwoPi * fs, 2) * c);
  b.r_ohm = kTwoPi * fs * b.l_h / q;
  return b;
}

// Three modes as a tube's: 26, 52 and 101 kHz above 4 nF with tan δ 0.01.
inline EquivalentCircuit tube_like() {
  EquivalentCircuit c;
  c.c0_f = 4e-9;
  c.tan_delta = 0.01;
  c.branches = {branch(26e3, 60, 0.15e-9), branch(52e3, 80, 0.6e-9), branch(101e3, 50, 0.08e-9)};
  return c;
}

}  // namespace piezo::dsp::test_networks
