#pragma once
// Fixture calibration of a capture: its calibration shots (role open, short,
// load; capture-format.md) → the channel skew, the measured standards, the
// fixture's physical quantities (dsp/fixture_calibration.hpp) and the
// compensation every estimator's Z(f) of the capture's "dut" shots gets
// (dsp/fixture_compensation.hpp). The one entry point for the impedance
// command, the pipeline and the gap diagnosis.
//
// Steps:
//  1. the shots of each role are averaged sample by sample (the drive repeats);
//  2. skew: from the open standard, whose v2 is smooth (it rises through
//     R1·Cp), by the fixture fit of the open alone, which separates the delay
//     from that lag (dsp/fixture_calibration.hpp); without an open, the
//     cross-correlation of the short (or load) record (±half a sample:
//     their v2 jumps with the drive, and a sampled jump has no sub-sample time);
//  3. channel 2 of every record (standards and dut) is deskewed in time,
//     the drive's jump kept on sample 0 (dsp::deskew_channel);
//  4. each standard's Z_m(f) is the direct FFT ratio of the whole deskewed,
//     differenced record (model-free: a standard's sub-microsecond time
//     constants are far outside any Prony band) on the bins of [fmin, 1.05·fmax],
//     smoothed by dsp::fit_standard, and all of them together give the
//     fixture's measured quantities (dsp::fit_fixture);
//  5. estimates of the deskewed dut records are compensated (compensate()).
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "acquisition/capture.hpp"
#include "dsp/fixture_calibration.hpp"
#include "dsp/fixture_compensation.hpp"
#include "dsp/impedance_types.hpp"

namespace piezo::acq {

// A divider record that owns its samples (an average of shots, a deskewed copy).
struct OwnedRecord {
  std::vector<double> v1, v2;
  double sample_rate_hz = 0.0, r1_ohm = 0.0;
  std::size_t pretrigger_samples = 0;
  std::optional<double> daq_range_v, v2_range_v;  // as in dsp::DividerRecord
  std::vector<std::string> shots;  // names of the shots in it
  dsp::DividerRecord view() const {
    return {v1, v2, sample_rate_hz, r1_ohm, pretrigger_samples, daq_range_v, v2_range_v};
  }
};

// True when two shots can be averaged sample by sample (same record and drive).
bool same_drive(const Shot& a, const Shot& b);

// The sample-by-sample average of `shots` (all must satisfy same_drive with the
// first; throws std::invalid_argument naming the first that does not).
OwnedRecord average_shots(const Capture& cap, std::span<const Shot* const> shots);

// Removes a channel-2 delay from a record (dsp::deskew_channel, jump at t = 0),
// also for a zero delay (channel 2's sample on the jump is then replaced by
// the value just after it, as channel 1 records it); the last ⌈skew·fs⌉ + 2
// samples, which channel 2 never recorded, are dropped from both channels.
void deskew_record(OwnedRecord& r, double skew_s);

struct CaptureCalibrationOptions {
  double fmin_hz =
      0.0;  // band of the standards; must cover the band the estimates are corrected over
  double fmax_hz = 0.0;                    // 0: fs/4
  int degree = 4;                          // of the standards' smoothing polynomials
  std::optional<dsp::FixtureModel> model;  // empty: the most complete the standards allow
  bool deskew = true;                      // estimate and remove the channel skew
};

struct CaptureCalibration {
  dsp::FixtureCalibration fixture;  // measured quantities (for the report and the gap diagnosis)
  dsp::FixtureModel model = dsp::FixtureModel::None;
  std::string model_description;                       // dsp::describe(model)
  std::optional<dsp::StandardModel> open, shrt, load;  // deskewed, smoothed standards
  dsp::LoadStandard load_value;
  double skew_applied_s = 0.0;  // removed from channel 2 of every record (deskew_record)
  std::string skew_source;  // "open standard (fixture fit)", "cross-correlation of the short", ...
  double r1_nominal_ohm = 0.0;
  std::vector<std::string> shots_open, shots_short, shots_load;  // shot names used
  std::vector<std::string> notes;                                // e.g. shots left out and why

  bool deskewed = true;  // the standards' records went through deskew_record
  // A dut shot (or average) as the estimators must see it: channel 2 deskewed
  // (like the standards' records).
  void prepare(OwnedRecord& r) const {
    if (deskewed) deskew_record(r, skew_applied_s);
  }
  // Compensates, in place, an estimate made from prepared records (Z and z_sigma_ohm).
  void compensate(dsp::ImpedanceResult& r) const;
  dsp::FixtureCompensation compensation() const;
};

// std::nullopt when the capture has no calibration shot. Throws
// std::invalid_argument naming the shot and the problem for unusable
// calibration shots (all clipped, a load without load_ohm, two different
// load standards, a model the shots present do not support).
std::optional<CaptureCalibration> calibrate_from_capture(const Capture& cap,
                                                         const CaptureCalibrationOptions& opt);

}  // namespace piezo::acq
