#pragma once
// Rayleigh damping C = αM + βK from the damping ratios of two modes, seed
// eqs 166-169: ξ_n = ½(α/ω_n + βω_n) solved for α, β. A negative α or β is
// not a damping model (it feeds energy into some band): refused, with the
// reason, instead of being used.
#include <string>

#include "model/port_model.hpp"

namespace piezo::update {

struct RayleighFit {
  bool ok = false;
  std::string message;             // why not, when !ok
  model::RayleighDamping damping;  // α (1/s), β (s); the raw solution even when refused
};

RayleighFit rayleigh_from_damping(double f1_hz, double zeta1, double f2_hz, double zeta2);

}  // namespace piezo::update
