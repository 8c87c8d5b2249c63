#pragma once
// The divider bench as a linear state-space system, exact in time: the tube
// in modal form (model::ModalPortModel), R1, and the circuit effects of the
// catalogue (series resistance, parallel capacitance, DAQ input resistance,
// dielectric loss as a causal Debye network). Input: the generator voltage
// v1(t), piecewise linear; output: the terminal voltage v2 seen by the DAQ.
//
// Tube port (see model/port_model.hpp): Q = Ce·vt + Σ p_k x_k,
//   x_k'' + c_k x_k' + ω_k² x_k = p_k vt,  Ce = C0 + C_res,  c_k = α + β κ_k,
// so Q/V = Ce + Σ p_k² / (ω_k² − ω² + jω c_k) as in the harmonic analysis.
// c_k also takes the port's per-mode radiation damping (PortMode::
// radiation_damping, 0 unless the simulator asked for an acoustic load), and
// parasitic R-L-C branches across the terminals enter as extra terms of the
// same sum (acquisition/parasitic_branch.hpp): issue 21's out-of-catalogue
// causes, simulator inputs only.
// Integration is exact for piecewise-linear input: one matrix exponential of
// the system augmented by the input and its slope per distinct step length.
#include <Eigen/Dense>
#include <complex>
#include <functional>
#include <map>
#include <span>
#include <vector>

#include "acquisition/parasitic_branch.hpp"
#include "drivers/sim/bench_physics.hpp"
#include "model/effects.hpp"
#include "model/port_model.hpp"
#include "model/seed_circuit.hpp"

namespace piezo::acq {

struct BenchCircuit {
  double r1_ohm = model::kSeedR1Ohm;  // the TRUE series resistor (nominal·(1 + r1_tolerance))
  double series_resistance_ohm = 0.0;
  double parallel_capacitance_f = 0.0;
  double daq_input_resistance_ohm = std::numeric_limits<double>::infinity();
  // tan δ of εT33 with the causal constant-phase law (model::port_capacitance
  // with dielectric_constant_phase), realised by a Debye network on Ce.
  double dielectric_loss = 0.0;
  model::RayleighDamping damping;
  double extra_damping_ratio = 0.0;  // mechanical_damping effect: c_k += 2 ξ_m ω_k
  // What sits at the terminals: the tube (the port model), or a calibration
  // standard in the same fixture (fixture_standard_circuit.cpp): open
  // (nothing), short (the terminals joined) or a load R ∥ C. The fixture is
  //   v1 ──[R1]──● v2 ──[series_resistance]──● terminals ── DUT ── GND
  //              ├─ parallel_capacitance ─ GND
  //              └─ daq_input_resistance ─ GND
  drivers::sim::DutSelection dut;
  // Out of the catalogue (issue 21): series R-L-C branches in parallel with
  // the tube port, inside the series lead resistance (at the terminals). They
  // belong to the transducer: a calibration standard in its place has none.
  std::vector<ParasiticBranch> parasitic_branches;
};

class DividerStateSpace {
 public:
  DividerStateSpace(const model::ModalPortModel& port, const BenchCircuit& circuit);

  // v2 at the given instants for generator voltage v1 (at rest before v1's first knot).
  std::vector<double> simulate(const drivers::sim::PiecewiseLinear& v1, std::span<const double> times);

  // Frequency response v2/v1 of the same system (for tests: the time domain
  // must agree with it), and the terminal impedance the DAQ would see.
  std::complex<double> transfer(double omega) const;

  int order() const { return static_cast<int>(a_.rows()); }

 private:
  // Open/short/load instead of the tube (fixture_standard_circuit.cpp).
  void build_standard(const BenchCircuit& circuit);

  struct Step {
    Eigen::MatrixXd phi;
    Eigen::VectorXd g0, g1;  // response to the input value and to its slope
  };
  const Step& step(double h);

  Eigen::MatrixXd a_;
  Eigen::VectorXd b_;  // input v1
  Eigen::RowVectorXd c_;  // output v2 = c·X + d·v1
  double d_ = 0.0;
  std::map<long long, Step> cache_;  // key: step length in femtoseconds
};

// A capacitor C_inf in parallel with Debye branches (series R–C, C_i and
// τ_i = R_i C_i): C(ω) = C_inf + Σ C_i/(1 + jωτ_i). Causal by construction.
struct DebyeNetwork {
  double c_inf = 0;
  std::vector<std::pair<double, double>> branches;  // (C_i, τ_i)
  std::complex<double> capacitance(double omega) const;
};

// The network whose C(ω) approximates the constant-phase lossy capacitance of
// model::lossy_capacitance(c, tanδ, ω) over [f_lo, f_hi] (non-negative least
// squares, relative error). tanδ = 0 gives C_inf = c and no branches.
DebyeNetwork debye_network_for_loss(double c, double tan_delta, double f_lo = 100.0, double f_hi = 1e6);
// … or any causal target C(ω) (model::port_capacitance of the tube).
DebyeNetwork debye_network_fit(const std::function<std::complex<double>(double)>& target, double f_lo = 100.0,
                               double f_hi = 1e6);

}  // namespace piezo::acq
