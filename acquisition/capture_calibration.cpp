#include "acquisition/capture_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "acquisition/divider_record.hpp"
#include "dsp/deskew.hpp"
#include "dsp/fft_ratio.hpp"
#include "dsp/signal_stats.hpp"

namespace piezo::acq {

bool same_drive(const Shot& a, const Shot& b) {
  return a.samples() == b.samples() && a.sample_rate_hz == b.sample_rate_hz &&
         a.pretrigger_samples == b.pretrigger_samples && a.excitation == b.excitation &&
         a.amplitude_v == b.amplitude_v && a.decay_per_s == b.decay_per_s &&
         a.frequency_hz == b.frequency_hz && a.f_start_hz == b.f_start_hz &&
         a.f_stop_hz == b.f_stop_hz;
}

OwnedRecord average_shots(const Capture& cap, std::span<const Shot* const> shots) {
  if (shots.empty()) throw std::invalid_argument("average_shots: no shot");
  const Shot& first = *shots.front();
  OwnedRecord r;
  r.v1.assign(first.samples(), 0.0);
  r.v2.assign(first.samples(), 0.0);
  for (const Shot* s : shots) {
    if (!same_drive(first, *s))
      throw std::invalid_argument("shot " + s->name + ": its record or drive differs from shot " +
                                  first.name + ", so the two cannot be averaged");
    for (std::size_t i = 0; i < r.v1.size(); ++i) {
      r.v1[i] += s->v1[i];
      r.v2[i] += s->v2[i];
    }
    r.shots.push_back(s->name);
  }
  const double n = double(shots.size());
  for (std::size_t i = 0; i < r.v1.size(); ++i) {
    r.v1[i] /= n;
    r.v2[i] /= n;
  }
  const auto rec = divider_record(cap, first);
  r.sample_rate_hz = rec.sample_rate_hz;
  r.r1_ohm = rec.r1_ohm;
  r.pretrigger_samples = rec.pretrigger_samples;
  for (const Shot* s : shots)  // one full scale only when every shot has the same
    if (s->range_v(1) != first.range_v(1) || s->range_v(2) != first.range_v(2)) return r;
  r.daq_range_v = first.range_v(1);
  r.v2_range_v = first.range_v(2);
  return r;
}

void deskew_record(OwnedRecord& r, double skew_s) {
  // The drive leaves its idle level at the last pretrigger sample (t = -dt)
  // and ramps to its first value at t = 0 (the simulated AWG joins its samples
  // linearly from idle; a real AWG's reconstruction is smoother still, and the
  // capture format does not fix it): channel 2 is idle before that kink and is
  // never interpolated across it.
  const std::size_t onset = r.pretrigger_samples > 0 ? r.pretrigger_samples - 1 : 0;
  r.v2 = dsp::deskew_channel(r.v2, r.sample_rate_hz, onset, skew_s);
  // The last samples of a late channel 2 would be extrapolated beyond its record
  // (noise amplified by the Lagrange weights): both channels end before them.
  const double d = skew_s * r.sample_rate_hz;
  const std::size_t drop = static_cast<std::size_t>(std::ceil(std::max(d, 0.0))) + 2;
  if (r.v1.size() < r.pretrigger_samples + drop + 16)
    throw std::invalid_argument("deskew_record: the record is too short for a skew of " +
                                std::to_string(skew_s * 1e9) + " ns");
  r.v1.resize(r.v1.size() - drop);
  r.v2.resize(r.v2.size() - drop);
}

namespace {

bool clipped(const Shot& s) {
  dsp::ClipDetection c1, c2;
  c1.range_v = s.range_v(1);
  c2.range_v = s.range_v(2);
  return dsp::compute_stats(s.v1, c1).clipped || dsp::compute_stats(s.v2, c2).clipped;
}

// The usable transient shots of one role, averaged: those matching the first
// in record and drive; clipped and sine shots are left out (with a note).
std::optional<OwnedRecord> average_role(const Capture& cap, Role role,
                                        std::vector<std::string>& notes) {
  std::vector<const Shot*> use;
  const std::string rn(to_string(role));
  for (const auto& s : cap.shots) {
    if (s.role != role) continue;
    if (s.excitation == Excitation::Sine) {
      notes.push_back("shot " + s.name + " (" + rn +
                      "): sine shots are not used for the fixture calibration");
    } else if (clipped(s)) {
      notes.push_back("shot " + s.name + " (" + rn + "): clipped, left out of the calibration");
    } else if (!use.empty() && !same_drive(*use.front(), s)) {
      notes.push_back("shot " + s.name + " (" + rn + "): record or drive differs from shot " +
                      use.front()->name + ", left out of the average");
    } else {
      if (role == Role::Load && !s.load_ohm)
        throw std::invalid_argument("shot " + s.name + ": role \"load\" without load_ohm");
      if (role == Role::Load && !use.empty() &&
          (s.load_ohm != use.front()->load_ohm ||
           s.load_parallel_f != use.front()->load_parallel_f))
        throw std::invalid_argument(
            "shot " + s.name + ": load standard differs from shot " + use.front()->name +
            " (load_ohm/load_parallel_f); one capture holds one load standard");
      use.push_back(&s);
    }
  }
  if (use.empty()) return std::nullopt;
  return average_shots(cap, use);
}

// Z_m(f) of a standard by the FFT ratio of the whole record, with channel 2's
// delay `skew_s` removed in the frequency domain (T = T_m·e^{+jωτ}): exact up
// to aliasing, where resampling the record would interpolate across the
// drive's kinks. nullopt: channel 2 shows no signal at all (an ideal short: Z_m = 0).
std::optional<dsp::MeasuredStandard> measure(const OwnedRecord& r, double fmin, double fmax,
                                             Role role, double skew_s = 0.0) {
  dsp::FftRatioOptions o;
  o.fmin_hz = fmin;
  o.fmax_hz = fmax;
  // The record's last sample enters every bin of the differenced spectra whole:
  // its noise, common to all bins, was 0.08 % of the load standard's |Z| below
  // 10 kHz (scatter over seeds) and the standards' smoothing fit, which takes
  // the bins as independent, cannot average it out. From a quadratic fit to the
  // last 1000 samples (the drive's decay is smooth there) it is ~10x smaller.
  o.end_fit_samples = 1000;
  try {
    auto z = dsp::impedance_fft(r.view(), o);
    if (skew_s != 0.0) dsp::deskew_impedance(z, r.r1_ohm, skew_s);
    return dsp::MeasuredStandard{z.f_hz, z.z_ohm, z.z_sigma_ohm};
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    if (role == Role::Short && what.find("v2 is constant") != std::string::npos)
      return std::nullopt;
    throw std::invalid_argument("calibration standard '" + std::string(to_string(role)) +
                                "' (shot " + r.shots.front() + "): " + what);
  }
}

}  // namespace

dsp::FixtureCompensation CaptureCalibration::compensation() const {
  return dsp::FixtureCompensation(model, open, shrt, load, load_value);
}

void CaptureCalibration::compensate(dsp::ImpedanceResult& r) const { compensation().apply(r); }

std::optional<CaptureCalibration> calibrate_from_capture(const Capture& cap,
                                                         const CaptureCalibrationOptions& opt) {
  CaptureCalibration out;
  auto open = average_role(cap, Role::Open, out.notes);
  auto shrt = average_role(cap, Role::Short, out.notes);
  auto load = average_role(cap, Role::Load, out.notes);
  if (!open && !shrt && !load) {
    bool any = false;
    for (const auto& s : cap.shots) any = any || s.role != Role::Dut;
    if (any)
      throw std::invalid_argument(
          "the capture's calibration shots are all unusable: " +
          (out.notes.empty() ? std::string("none left") : out.notes.front()));
    return std::nullopt;
  }
  const OwnedRecord& ref = open ? *open : shrt ? *shrt : *load;
  const double fs = ref.sample_rate_hz;
  double fmax = opt.fmax_hz > 0 ? opt.fmax_hz : fs / 4;
  if (!(fmax <= fs / 2))
    throw std::invalid_argument("calibration: fmax above the Nyquist frequency of the standards");
  fmax =
      std::min(fs / 2, 1.05 * fmax);  // a few bins beyond the band: the models must cover its top
  out.r1_nominal_ohm = cap.setup.divider_r1_ohm;
  if (open) out.shots_open = open->shots;
  if (shrt) out.shots_short = shrt->shots;
  if (load) {
    out.shots_load = load->shots;
    const Shot* first = nullptr;
    for (const auto& s : cap.shots)
      if (s.name == load->shots.front()) first = &s;
    out.load_value = {*first->load_ohm, first->load_parallel_f.value_or(0.0)};
  }

  // 2. The skew.
  if (opt.deskew) {
    if (open) {
      dsp::CalibrationStandards c0;
      c0.r1_nominal_ohm = out.r1_nominal_ohm;
      c0.open = measure(*open, opt.fmin_hz, fmax, Role::Open);
      out.skew_applied_s = dsp::fit_fixture(c0).skew_s.value_or(0.0);
      out.skew_source =
          "open standard (fixture fit of its transfer: delay separated from the R1*Cp lag)";
    } else {
      const OwnedRecord& r = shrt ? *shrt : *load;
      const auto pre = r.pretrigger_samples;
      out.skew_applied_s =
          dsp::xcorr_delay(std::span(r.v1).subspan(pre), std::span(r.v2).subspan(pre), fs);
      out.skew_source = std::string("cross-correlation of the ") + (shrt ? "short" : "load") +
                        " standard (no open: +-half a sample, its v2 jumps with the drive)";
    }
  } else {
    out.skew_source = "not estimated (deskew off)";
  }
  out.deskewed = opt.deskew;

  // 4. Standards (deskewed), fixture quantities, smooth models.
  const double sk = opt.deskew ? out.skew_applied_s : 0.0;
  dsp::CalibrationStandards cs;
  cs.r1_nominal_ohm = out.r1_nominal_ohm;
  cs.load_value = out.load_value;
  cs.skew_guess_s = 0.0;  // the standards are deskewed: the fit sees the residual
  if (open) cs.open = measure(*open, opt.fmin_hz, fmax, Role::Open, sk);
  bool short_is_zero = false;
  if (shrt) {
    cs.shrt = measure(*shrt, opt.fmin_hz, fmax, Role::Short, sk);
    short_is_zero = !cs.shrt;
  }
  if (load) cs.load = measure(*load, opt.fmin_hz, fmax, Role::Load, sk);
  if (cs.open || cs.shrt || cs.load) out.fixture = dsp::fit_fixture(cs);
  // A fixture no bench has: R1 off its value by more than a resistor's
  // tolerance allows, a capacitance across the DUT below zero or above 10 nF,
  // channel 2 microseconds late. The standards' records then do not show the
  // standards (mains hum or a baseline wander on a short's millivolts, a
  // standard not connected as labelled): refused, never used to correct.
  {
    const auto& f = out.fixture;
    std::string bad;
    char b[160];
    if (f.r1_error && std::abs(*f.r1_error) > 0.10) {
      std::snprintf(b, sizeof b, "R1 off by %+.1f %% (beyond any resistor's tolerance, 10 %%)", 100 * *f.r1_error);
      bad += b;
    }
    if (f.fixture_capacitance_f && (*f.fixture_capacitance_f < -50e-12 || *f.fixture_capacitance_f > 10e-9)) {
      std::snprintf(b, sizeof b, "%scapacitance across the transducer %.0f pF (outside -50 pF ... 10 nF)",
                    bad.empty() ? "" : ", ", 1e12 * *f.fixture_capacitance_f);
      bad += b;
    }
    if (!bad.empty())
      throw std::invalid_argument("calibration: the standards give a fixture no bench has: " + bad +
                                  " - their records do not show the standards (hum or a baseline wander on "
                                  "the short's millivolts, or a standard not connected as labelled)");
  }
  if (out.fixture.skew_s) {  // total delay of channel 2: removed from the records + what the fit
                             // still sees
    out.fixture.skew_s = *out.fixture.skew_s + out.skew_applied_s;
  } else {
    out.fixture.skew_s = out.skew_applied_s;
  }
  if (short_is_zero) {
    out.fixture.lead_resistance_ohm = 0.0;
    out.notes.push_back(
        "the short standard shows no voltage on channel 2: lead resistance below the DAQ's "
        "resolution, "
        "taken as 0");
  }

  out.model = opt.model.value_or(
      dsp::FixtureCompensation::best_model(open.has_value(), shrt.has_value(), load.has_value()));
  out.model_description = dsp::describe(out.model);
  // Open and load as admittances (G + jωC after the error box), the short as an impedance (R +
  // jωL).
  if (cs.open) out.open = dsp::fit_standard(*cs.open, true, opt.degree, "open");
  if (cs.load) out.load = dsp::fit_standard(*cs.load, true, opt.degree, "load");
  if (cs.shrt) out.shrt = dsp::fit_standard(*cs.shrt, false, opt.degree, "short");
  if (short_is_zero) {  // Z_s ≡ 0
    dsp::StandardModel z;
    z.fmax_hz = fmax;
    z.omega_scale = 2 * M_PI * fmax;
    z.c = Eigen::VectorXd::Zero(opt.degree + 1);
    z.cov = Eigen::MatrixXd::Zero(opt.degree + 1, opt.degree + 1);
    out.shrt = z;
  }
  (void)out.compensation();  // checks that the model is supported by the standards present
  return out;
}

}  // namespace piezo::acq
