#pragma once
// What the simulated bench needs from physics: the voltage at the transducer
// terminal (v2) at given instants, for a generator voltage v1 given as a
// piecewise-linear function (knots; two knots at the same instant make a
// jump, such as the step at t = 0 of an exp_decay burst). The circuit is at
// rest before the first knot. The FE-based implementation lives in
// acquisition/ (it needs model/); drivers/ stays free of the model.
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace piezo::drivers::sim {

struct PiecewiseLinear {
  std::vector<double> t;  // non-decreasing
  std::vector<double> v;
  double at(double time) const;  // right-continuous value
};

// What sits at the transducer terminals (simulator only: a real bench has a
// technician swap it, see acquisition/calibration_run.hpp). The fixture (lead
// resistance, fixture capacitance, DAQ input) stays in place for every kind.
struct DutSelection {
  enum class Kind { Tube, Open, Short, Load };
  Kind kind = Kind::Tube;
  double load_ohm = 0.0;  // Load: its resistance (> 0)
  double load_parallel_f = 0.0;  // Load: its parallel capacitance (>= 0)
};

// Multipliers of the transducer's YE11, εT33 and d31 against their nominal
// values: the drift and step disturbances (drivers/sim/disturbances.hpp).
struct ConstantFactors {
  double y_e11 = 1.0;
  double eps_t33 = 1.0;
  double d31 = 1.0;
  bool operator==(const ConstantFactors&) const = default;
};

class BenchPhysics {
 public:
  virtual ~BenchPhysics() = default;
  // `sample_times` ascending, all >= knots.t.front(); v1 is held at its last
  // knot value after the last knot.
  virtual std::vector<double> respond(const PiecewiseLinear& v1, std::span<const double> sample_times) = 0;
  // Ground truth recorded in simulated captures (/truth), never read by estimators.
  virtual std::vector<std::pair<std::string, double>> truth() const { return {}; }
  virtual std::string description() const = 0;
  // Swaps the device at the terminals. Returns "" on success, else why not.
  virtual std::string select_dut(const DutSelection&) { return "this simulated bench cannot swap its device"; }
  // Changes the transducer's constants (all factors 1: the nominal
  // transducer); the device at the terminals stays selected. Returns "" on
  // success, else why not.
  virtual std::string set_constant_factors(const ConstantFactors&) {
    return "this simulated bench cannot change its transducer's constants";
  }
};

}  // namespace piezo::drivers::sim
