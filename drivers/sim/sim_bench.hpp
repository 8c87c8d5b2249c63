#pragma once
// The simulated bench: an AWG and a DAQ that share one physical set-up. The
// SCPI faces (sim_awg, sim_daq) only parse commands and update the state
// here; acquire() turns a triggered burst into a DAQ record: physics for v2,
// then the DAQ's own imperfections (channel skew and gain, white noise per
// channel, ADC quantisation and range clipping), all seeded; optionally a
// real bench's slow disturbances (drivers/sim/disturbances.hpp: offsets, hum,
// pink noise, trigger jitter, drift and steps of the transducer's constants).
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <random>
#include <vector>

#include "drivers/sim/bench_physics.hpp"
#include "drivers/sim/disturbances.hpp"

namespace piezo::drivers::sim {

struct DaqImperfections {
  double channel_skew_s = 0.0;  // channel 2 samples this much later than channel 1
  double channel_gain = 0.0;  // relative gain error of channel 2 (0.01 = +1 %)
  double noise_rel[2] = {0.0, 0.0};  // std(noise)/std(clean signal), per channel (seed's definition)
  double noise_v[2] = {0.0, 0.0};  // absolute white-noise floor, volts rms
  int adc_bits = 14;
};

// Faults injected on purpose, for the fault tests (same over TCP and in-process).
// The Comedi* kinds are the simulated Comedi board's (drivers/sim/sim_comedi_board.*).
struct FaultPlan {
  enum class Kind {
    None,
    CloseMidFetch,
    NoReplyToFetch,
    MalformedBlock,
    TruncatedBlock,
    ErrorOnConfigure,
    ComediOverrun,     // read() fails with EPIPE a third of the way through the shot
    ComediNoData,      // the board never delivers the shot's samples (read times out)
    ComediDeviceGone,  // read() fails with ENODEV a third of the way through, and so does all after
  };
  Kind kind = Kind::None;
  int at_shot = 0;  // 0-based index of the acquisition that fails
};

struct AwgState {
  std::vector<float> arb;  // normalised samples of the selected arb
  double arb_rate_hz = 1e6;
  double vpp = 1.0;
  double offset_v = 0.0;
  bool output_on = false;
  bool burst_on = false;
  bool bus_trigger = false;
};

struct DaqState {
  double sample_rate_hz = 1e7;
  std::size_t points = 1000;
  double position_s = 0.0;  // :TIMebase:POSition with reference LEFT
  double full_scale_v[2] = {8.0, 8.0};  // :CHANnel<n>:RANGe (8 divisions)
  bool aux_trigger = true;
  bool armed = false;
  bool done = false;
  std::vector<std::int16_t> codes[2];
  double yincrement[2] = {1.0, 1.0};
};

class SimBench {
 public:
  // Throws std::invalid_argument on invalid imperfections or disturbances, or
  // when the disturbances change the device and the physics cannot.
  SimBench(std::unique_ptr<BenchPhysics> physics, DaqImperfections daq, std::uint64_t seed,
           FaultPlan faults = {}, Disturbances disturbances = {});

  // Called by the AWG face on *TRG: runs one acquisition if the DAQ is armed.
  void fire();

  std::mutex& mutex() { return mu_; }
  AwgState& awg() { return awg_; }
  DaqState& daq() { return daq_; }
  const FaultPlan& faults() const { return faults_; }
  int acquisitions() const { return acquisitions_; }
  int fetches_started() const { return fetches_; }
  void count_fetch() { ++fetches_; }
  const BenchPhysics& physics() const { return *physics_; }
  // SIM:DUT (simulator-only command): swaps the device at the terminals.
  // Caller holds mutex(). Returns "" on success, else the reason.
  std::string select_dut(const DutSelection& d);
  const DutSelection& dut() const { return dut_; }
  const DaqImperfections& imperfections() const { return imp_; }
  std::uint64_t seed() const { return seed_; }

  const Disturbances& disturbances() const { return dist_; }
  // The DC offset of channel 1 or 2 (0 without the offset disturbance).
  double channel_offset_v(int channel) const { return offset_v_[channel - 1]; }
  // The capture's next acquisitions belong to shot `shot` (0-based) of
  // `shots`: the drift and step disturbances follow the capture's shots (the
  // runner calls this before each shot; unrecorded probe shots take the
  // next shot's index). Never called: the acquisitions are counted, and no
  // drift is applied (its N is unknown). Takes mutex().
  void set_capture_position(int shot, int shots);
  // What was applied to the latest acquisition (all zero/one before any).
  ShotDisturbances last_disturbances();

 private:
  // The AWG output as knots, from `t_begin` (before the trigger) on.
  PiecewiseLinear generator_knots(double t_begin, double t_end) const;
  // Draws this acquisition's disturbances and sets the physics' constants.
  ShotDisturbances draw_disturbances();
  // Offset + hum + pink noise of channel `ch` for samples at t_k (nominal
  // instants), pink scaled to `clean_std`.
  std::vector<double> additive_disturbance(int ch, const ShotDisturbances& sd,
                                           const std::vector<double>& t, double clean_std);

  std::mutex mu_;
  std::unique_ptr<BenchPhysics> physics_;
  DaqImperfections imp_;
  std::uint64_t seed_;
  std::mt19937_64 rng_;
  FaultPlan faults_;
  Disturbances dist_;
  std::mt19937_64 dist_rng_;  // the disturbances' own stream: off leaves rng_'s draws as they were
  double offset_v_[2] = {0.0, 0.0};
  int capture_shot_ = -1, capture_shots_ = 0;  // set_capture_position (-1: not told)
  ConstantFactors factors_;  // the physics' current constants
  ShotDisturbances last_;
  AwgState awg_;
  DaqState daq_;
  int acquisitions_ = 0;
  int fetches_ = 0;
  DutSelection dut_;
};

}  // namespace piezo::drivers::sim
