#pragma once
// A simulated Comedi board: the seam of drivers/comedi/board.hpp over the
// shared SimBench, so the comedi driver records the simulated bench's
// samples. It models an NI PCI-6110 under ni_pcimio as far as the driver
// sees it: analog input on subdevice 0, 4 simultaneously sampled
// differential channels, 12-bit (maxdata 4095, sampl_t), the range table
// ±50, ±20, ±10, ±5, ±2, ±1, ±0.5, ±0.2 V, a 20 MHz timebase (scan periods
// in 50 ns steps, at least 200 ns: 5 MS/s), start on an edge of PFI0..9
// (the AWG's marker; the bench's burst starts at the trigger, so sample 0
// is the burst's first sample). Raw values are the bench's 12-bit codes in
// offset binary (code + 2048). Optionally soft-calibrated (as an M-series
// board with a calibration file is): the polynomial is then the ideal one,
// volts = (raw − 2048) · range / 2048, which gives the embedded bench's
// volts exactly; without it the driver uses comedi_to_phys (min + (max −
// min) · raw / 4095), as on a real E-series board.
// What it does not model: software start (command_test refuses TRIG_NOW at
// stage 1: the simulated bench has no clock to place the burst in a
// free-running record), single-ended references (the 6110's inputs are
// differential only: stage 5), waiting (a read before the burst times out at
// once, without sleeping). Faults: FaultPlan's Comedi* kinds.
#include <memory>
#include <string>
#include <vector>

#include "drivers/comedi/board.hpp"
#include "drivers/sim/sim_bench.hpp"

namespace piezo::drivers::sim {

class SimComediBoard : public comedi::Board {
 public:
  // The bench must quantise with 12 bits (the board's ADC); throws std::invalid_argument otherwise.
  SimComediBoard(std::shared_ptr<SimBench> bench, std::string path, bool soft_calibrated = false);

  std::string path() const override { return path_; }
  std::string driver_name() const override { return "ni_pcimio"; }
  std::string board_name() const override { return "pci-6110"; }
  int find_analog_input() override { return 0; }
  comedi::SubdeviceInfo subdevice(unsigned subdev) override;
  std::vector<comedi::Range> ranges(unsigned subdev, unsigned channel) override;
  std::uint32_t maxdata(unsigned subdev, unsigned channel) override;
  std::optional<comedi::Polynomial> softcal(unsigned subdev, unsigned channel,
                                            unsigned range) override;
  int command_test(comedi::Command& c) override;
  int command(const comedi::Command& c) override;
  comedi::ReadResult read(std::span<std::uint8_t> buf, double timeout_s) override;
  void cancel(unsigned subdev) override;
  int last_error() const override { return errno_; }
  std::string error_text(int error) const override;
  double to_phys(std::uint32_t raw, const comedi::Range& r, std::uint32_t maxdata) const override {
    return comedi::linear_to_phys(raw, r, maxdata);
  }
  double to_physical(std::uint32_t raw, const comedi::Polynomial& p) const override {
    return comedi::polynomial_to_phys(raw, p);
  }

  int commands() const { return commands_; }  // comedi_command calls accepted
  int cancels() const { return cancels_; }    // comedi_cancel calls

 private:
  void fill_stream();  // the shot's interleaved raw samples (caller holds the bench mutex)

  std::shared_ptr<SimBench> bench_;
  std::string path_;
  bool soft_calibrated_;
  bool running_ = false;
  bool gone_ = false;
  int errno_ = 0;
  int armed_at_ = 0;  // the bench's acquisition count when the command started
  int shot_ = -1;     // the bench's acquisition index of the running command
  std::vector<std::uint8_t> stream_;
  std::size_t read_pos_ = 0;
  bool filled_ = false;
  int commands_ = 0;
  int cancels_ = 0;
};

}  // namespace piezo::drivers::sim
