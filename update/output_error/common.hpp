#pragma once
// What every part of the output-error fit (update/output_error.hpp) shares:
// the count of its coordinates, the complex type of its spectra and the
// exception its preconditions throw. Internal to update/output_error/.
#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>

namespace piezo::update::oe {

inline constexpr double kTwoPi = 2.0 * M_PI;
using cd = std::complex<double>;
// The fit's coordinates: ln YE11, nu12 (relative), ln d31, ln εT33, ln β (or ln η, η = 1/Qm).
inline constexpr int kParams = 5;

// Unusable data (fit_output_error and predict_output_error alike).
[[noreturn]] inline void fail(const std::string& msg) {
  throw std::invalid_argument("fit_output_error: " + msg);
}

}  // namespace piezo::update::oe
