#pragma once
// The seam under the Comedi driver: the few comedilib calls it needs, on one
// opened /dev/comediN, in types of our own (no comedilib.h here). Two
// implementations: ComedilibBoard (comedilib_board.cpp, the only file that
// includes comedilib.h) and the simulated board (drivers/sim/sim_comedi_board.*),
// which produces the simulated bench's samples and can overrun, time out or
// disappear. Return conventions follow comedilib's, so the driver's error
// handling is the same against either.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace piezo::drivers::comedi {

// Analog reference of a channel (comedi.h AREF_*): RSE is AREF_GROUND.
enum class Aref { Ground, Common, Diff };

// One entry of a channel's range table (comedi_range), in volts.
struct Range {
  double min = 0.0, max = 0.0;
  bool volts = true;  // false: UNIT_mA or UNIT_none (the driver refuses those)
};

// A conversion polynomial (comedi_polynomial_t): phys = Σ c_i (raw − origin)^i.
struct Polynomial {
  std::vector<double> coefficients;  // at most 4 (COMEDI_MAX_NUM_POLYNOMIAL_COEFFICIENTS)
  double expansion_origin = 0.0;
};

struct SubdeviceInfo {
  unsigned n_channels = 0;
  bool soft_calibrated = false;  // SDF_SOFT_CALIBRATED
  std::size_t sample_bytes = 2;  // 2 (sampl_t) or 4 (SDF_LSAMPL: lsampl_t)
  bool can_stream = false;       // SDF_CMD_READ
};

struct ChanSpec {
  unsigned channel = 0;
  unsigned range = 0;  // index into the channel's range table
  Aref aref = Aref::Diff;
};

// A streaming acquisition (comedi_cmd), reduced to what the driver sets:
// start on TRIG_NOW (software) or TRIG_EXT (an edge on a PFI line), one scan
// per scan_period_ns (scan_begin TRIG_TIMER), the channels of a scan
// converted as the board does it (comedi_get_cmd_generic_timed decides:
// TRIG_NOW on simultaneous-sampling boards such as the 611x, else TRIG_TIMER),
// stop after `scans` scans (TRIG_COUNT).
struct Command {
  unsigned subdevice = 0;
  bool external_start = false;     // TRIG_EXT (else TRIG_NOW)
  unsigned start_pfi = 0;          // the PFI line of TRIG_EXT (NI numbering)
  bool start_falling = false;      // CR_INVERT: trigger on the falling edge
  unsigned scan_period_ns = 0;     // in: requested; out: what the board will do
  unsigned convert_period_ns = 0;  // out: 0 = simultaneous (TRIG_NOW)
  unsigned scans = 0;
  std::vector<ChanSpec> chanlist;
};

struct ReadResult {
  enum class Status { Data, End, Timeout, Error };
  Status status = Status::Data;
  std::size_t bytes = 0;  // Data: how many were read (> 0)
  int error = 0;          // Error: errno (EPIPE: buffer overrun; ENODEV: device gone)
};

class Board {
 public:
  virtual ~Board() = default;
  virtual std::string path() const = 0;         // "/dev/comedi0"
  virtual std::string driver_name() const = 0;  // comedi_get_driver_name ("ni_pcimio")
  virtual std::string board_name() const = 0;   // comedi_get_board_name ("pci-6110")
  // comedi_find_subdevice_by_type(COMEDI_SUBD_AI, 0); -1 if there is none.
  virtual int find_analog_input() = 0;
  virtual SubdeviceInfo subdevice(unsigned subdev) = 0;
  virtual std::vector<Range> ranges(unsigned subdev, unsigned channel) = 0;  // comedi_get_range
  virtual std::uint32_t maxdata(unsigned subdev, unsigned channel) = 0;      // comedi_get_maxdata
  // comedi_get_softcal_converter(COMEDI_TO_PHYSICAL) from the board's default
  // calibration file; nullopt when there is none (comedi_soft_calibrate not run).
  virtual std::optional<Polynomial> softcal(unsigned subdev, unsigned channel, unsigned range) = 0;
  // comedi_get_cmd_generic_timed, then the start/stop/chanlist of `c`, then
  // comedi_command_test; writes back the periods the board will use. Returns
  // comedilib's value: 0 valid, 1..5 the stage that failed or adjusted an
  // argument (3: argument fixed, 4: timer rounded, 5: chanlist), -1 error
  // (last_error()).
  virtual int command_test(Command& c) = 0;
  virtual int command(const Command& c) = 0;  // comedi_command: 0, or -1 (last_error())
  // Waits up to timeout_s for data (poll on comedi_fileno), then read()s.
  virtual ReadResult read(std::span<std::uint8_t> buf, double timeout_s) = 0;
  virtual void cancel(unsigned subdev) = 0;             // comedi_cancel; best effort
  virtual int last_error() const = 0;                   // comedi_errno
  virtual std::string error_text(int error) const = 0;  // comedi_strerror / strerror
  virtual double to_phys(std::uint32_t raw, const Range& r, std::uint32_t maxdata) const = 0;
  virtual double to_physical(std::uint32_t raw, const Polynomial& p) const = 0;
};

// Opens /dev/comediN through comedilib; throws InstrumentError naming the
// path and comedilib's reason (no such device, permission denied, ...).
std::unique_ptr<Board> open_comedilib_board(const std::string& path);

// comedilib's own formulas (lib/range.c, lib/calib.c), for simulated boards:
// to_phys = min + (max − min) · raw / maxdata; to_physical = Σ c_i (raw − origin)^i.
double linear_to_phys(std::uint32_t raw, const Range& r, std::uint32_t maxdata);
double polynomial_to_phys(std::uint32_t raw, const Polynomial& p);

}  // namespace piezo::drivers::comedi
