#pragma once
// Time-domain response of the tube, exact to the modal port model
// (model/port_model.hpp): each short-circuit mode is a 2nd-order system driven
// by the electrode voltage (a series R-L-C "motional" branch with
// L_k = 1/p_k², C_k = p_k²/ω_k², R_k = c_k/p_k²) in parallel with the clamped
// plus residual capacitance C0 + C_res. The resulting LTI system is discretised
// EXACTLY for inputs that are piecewise linear between samples (first-order
// hold, via one matrix exponential), so the output at the sample instants has
// no integration error — only the FE/modal model's own approximation.
//
// Divider of the bench (seed §5.2): v1 (AWG) → R1 → node 2 (measured v2) →
// [R_lead → transducer] → ground, with optional C_p and R_daq from node 2 to
// ground. State at rest at t = 0; v1 may start non-zero (a step at t = 0).
// Material Qm / tanδ are not representable in the time domain and are ignored;
// damping is Rayleigh (modal c_k = α + βκ_k), identical to the harmonic modal model.
#include <Eigen/Core>
#include <limits>
#include <span>
#include <vector>

#include "model/port_model.hpp"
#include "model/seed_circuit.hpp"

namespace piezo::model {

struct DividerCircuit {
  double r1_ohm = kSeedR1Ohm;  // series resistor (seed ch. 5 lab circuit)
  double c_parallel_f = 0.0;  // capacitance from node 2 to ground (cable, DAQ input)
  double r_lead_ohm = 0.0;    // series resistance between node 2 and the transducer
  double r_daq_ohm = std::numeric_limits<double>::infinity();  // DAQ input resistance at node 2
  void validate() const;  // throws std::invalid_argument
};

// ẋ = A x + B u, y = C x + D u, discretised for piecewise-linear u:
// x[n+1] = Φ x[n] + Γ0 u[n] + Γ1 (u[n+1] − u[n]).
class DiscreteLti {
 public:
  DiscreteLti() = default;
  DiscreteLti(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, const Eigen::RowVectorXd& c,
              double d, double dt);
  // y at every sample of u, from x(0) = 0.
  std::vector<double> run(std::span<const double> u) const;
  int order() const { return static_cast<int>(phi_.rows()); }

 private:
  Eigen::MatrixXd phi_;
  Eigen::VectorXd g0_, g1_;
  Eigen::RowVectorXd c_;
  double d_ = 0;
};

// Build once (one matrix exponential), run for many waveforms.
class DividerSimulator {
 public:
  DividerSimulator(const ModalPortModel& port, const RayleighDamping& damping,
                   const DividerCircuit& circuit, double sample_rate_hz);
  std::vector<double> simulate(std::span<const double> v1) const;  // v2 at the sample instants
  const DiscreteLti& system() const { return lti_; }

 private:
  DiscreteLti lti_;
};

// Electrode charge Q(t) for an arbitrary (sampled, piecewise-linear) electrode voltage.
class ChargeSimulator {
 public:
  ChargeSimulator(const ModalPortModel& port, const RayleighDamping& damping,
                  double sample_rate_hz);
  std::vector<double> simulate(std::span<const double> v) const;

 private:
  DiscreteLti lti_;
};

// One-shot conveniences.
std::vector<double> simulate_divider(const ModalPortModel& port, const RayleighDamping& damping,
                                     const DividerCircuit& circuit, std::span<const double> v1,
                                     double sample_rate_hz);
std::vector<double> simulate_charge(const ModalPortModel& port, const RayleighDamping& damping,
                                    std::span<const double> v, double sample_rate_hz);

// Steady-state v2/v1 of the divider at frequency f from the port model
// (the frequency-domain counterpart of DividerSimulator, used to verify it).
std::complex<double> divider_transfer(const ModalPortModel& port, const RayleighDamping& damping,
                                      const DividerCircuit& circuit, double f_hz);

}  // namespace piezo::model
