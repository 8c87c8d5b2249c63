#include "acquisition/channel2_response.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

#include "dsp/fft.hpp"

namespace piezo::acq {

Channel2Response channel2_response(const model::EffectSet& fx) {
  const model::EffectSet neutral;
  std::vector<std::pair<const model::EffectInfo*, double>> terms;
  for (const auto& e : model::effect_catalogue())
    if (e.stage == model::EffectStage::channel2 && !e.simulated_natively && e.term &&
        fx.*(e.field) != neutral.*(e.field))
      terms.emplace_back(&e, fx.*(e.field));
  if (terms.empty()) return {};
  return [terms](double omega) {
    std::complex<double> h = 1.0;
    for (const auto& [e, v] : terms) h *= e->term(v, omega);
    return h;
  };
}

void apply_channel2_response(std::span<double> v, double dt, const Channel2Response& h) {
  if (!h || v.empty()) return;
  if (!(dt > 0)) throw std::invalid_argument("apply_channel2_response: the sample interval must be > 0");
  const std::size_t n = dsp::good_fft_size(2 * v.size());
  dsp::RealFft fft(n);
  std::vector<std::complex<double>> x(fft.bins());
  fft.forward(v.data(), v.size(), x.data());
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double omega = 2 * M_PI * double(k) / (double(n) * dt);
    std::complex<double> hk = h(omega);
    // The Nyquist bin of an even n is real: a real filter's value there is too.
    if (n % 2 == 0 && k == n / 2) hk = hk.real();
    x[k] *= hk / double(n);
  }
  fft.inverse(x.data(), v.data(), v.size());
}

}  // namespace piezo::acq
