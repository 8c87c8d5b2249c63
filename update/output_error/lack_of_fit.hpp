#pragma once
// Lack of fit of the output-error fit: does the model class explain the
// capture? χ²/ν against what the noise estimate's own scatter allows, and the
// spectral test for a misfit concentrated in frequency (an end mass shifting
// a few modes); under a lack of fit, where the residual stands above the
// noise (update/residual_regions.hpp). Internal to update/output_error/.
#include <Eigen/Core>

#include "update/output_error.hpp"
#include "update/output_error/fitter.hpp"
#include "update/output_error/forward_model.hpp"

namespace piezo::update::oe {

struct SpectralTest {
  double log10_p = 0;  // Bonferroni-corrected, of the most significant window
  double f_lo = 0, f_hi = 0, excess = 1;
  int windows = 0;
};

// Lack of fit concentrated in frequency: the residual's periodogram over its
// expected noise shape, scaled by its own median (robust to the noise level's
// error), summed over windows of 1..64 bins; the window least likely under
// noise alone (log_gamma_tail, update/residual_regions.hpp), its chance
// multiplied by the number of windows tried.
SpectralTest spectral_lack_of_fit(const Eigen::VectorXd& r, const Eigen::VectorXd& shape,
                                  double bin_hz);

// The fit's verdict (OeOptions::lack_of_fit_z, lack_of_fit_p) into out:
// chi2_limit, lack_of_fit, the band test's numbers and, under a lack of fit,
// the regions. Reads out.chi2_per_dof and out.noise_dof.
void judge_lack_of_fit(const FitAnswer& answer, Problem& prob, const OeOptions& opt, OeResult& out);

}  // namespace piezo::update::oe
