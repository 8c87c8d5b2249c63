#pragma once
// Geometry of the radially poled tube transducer (seed §3.2) and the project's
// defaults: the tube of the reference document (published-tube-results.json),
// applied when a capture's /setup does not give its own.
#include <stdexcept>
#include <string>

namespace piezo::model {

struct TubeGeometry {
  double inner_diameter_m = 0.016;  // Di
  double outer_diameter_m = 0.019;  // Do
  double length_m = 0.020;          // L
  double density_kg_m3 = 7600.0;    // rho (APC850)

  double inner_radius() const { return 0.5 * inner_diameter_m; }
  double outer_radius() const { return 0.5 * outer_diameter_m; }

  // Throws std::invalid_argument naming the offending field.
  void validate() const {
    if (!(inner_diameter_m > 0.0))
      throw std::invalid_argument("TubeGeometry: inner_diameter_m must be > 0");
    if (!(outer_diameter_m > inner_diameter_m))
      throw std::invalid_argument("TubeGeometry: outer_diameter_m must exceed inner_diameter_m");
    if (!(length_m > 0.0)) throw std::invalid_argument("TubeGeometry: length_m must be > 0");
    if (!(density_kg_m3 > 0.0))
      throw std::invalid_argument("TubeGeometry: density_kg_m3 must be > 0");
  }
};

}  // namespace piezo::model
