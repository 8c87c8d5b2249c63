#pragma once
// Harmonic electrical admittance Y(ω) = jω·Q/V and impedance Z = 1/Y of the
// tube on any frequency list, two ways:
//  * modal superposition over the short-circuit modes (fast; model/port_model.hpp),
//  * direct complex sparse solve of the full coupled system (reference):
//      [K_UU(1 + j/Qm) + jω(αM + βK_UU) − ω²M,  K_UΦ        ] [U]   [0]
//      [K_ΦU,                                    K_ΦΦ(1−j tanδ)] [Φ] = [−Q e_V]
//    with V = 1 prescribed, Q = −(K_ΦU U + K_ΦΦ Φ)_V (eqs 79, 72).
// Y(0) = 0 is returned exactly (Z(0) = ∞).
#include <Eigen/SparseLU>
#include <complex>
#include <span>
#include <vector>

#include "model/assembler.hpp"
#include "model/port_model.hpp"
#include "model/tube_model.hpp"

namespace piezo::model {

using Complex = std::complex<double>;

// Y(f) by modal superposition; throws std::invalid_argument for f < 0.
std::vector<Complex> admittance_modal(const ModalPortModel& port, std::span<const double> freq_hz,
                                      const RayleighDamping& damping = {},
                                      const MaterialLosses& losses = {});

// Z = 1/Y element-wise (Y = 0 → Z = ∞ + 0j).
std::vector<Complex> impedance_from_admittance(std::span<const Complex> y);

// Evenly spaced grid fmin, fmin + step, … ≤ fmax (+ half-step tolerance).
std::vector<double> frequency_grid(double fmin_hz, double fmax_hz, double step_hz);

// Direct solve; keeps the sparse LU's symbolic analysis across frequencies
// and calls. One solver per thread.
class DirectHarmonicSolver {
 public:
  explicit DirectHarmonicSolver(const TubeModel& model);
  // end_mass_fraction: end-face mass loading, M → M + f·ΔM (model/end_mass.hpp).
  std::vector<Complex> admittance(const PiezoMaterialE& material, std::span<const double> freq_hz,
                                  const RayleighDamping& damping = {},
                                  const MaterialLosses& losses = {},
                                  double end_mass_fraction = 0.0);

 private:
  const TubeModel* model_;
  SpMatC a_;
  Eigen::SparseLU<SpMatC> lu_;
  bool analysed_ = false;
  std::vector<int> col_v_, row_v_;  // value positions of the electrode column / row
  int diag_v_ = -1;
};

}  // namespace piezo::model
