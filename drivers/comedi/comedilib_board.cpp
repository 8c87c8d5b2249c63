// The Comedi seam over comedilib: the only file that includes comedilib.h.
// Each method is one or two comedilib calls; the driver (driver.cpp) decides
// what they mean. Never run against a board here (no Comedi device on the
// machines this was written on); the calls follow comedilib 0.11's manual
// and its demo/cmd.c.
#include <comedilib.h>
#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "drivers/comedi/board.hpp"
#include "drivers/scpi_client.hpp"

namespace piezo::drivers::comedi {

namespace {

unsigned aref_bits(Aref a) {
  switch (a) {
    case Aref::Ground:
      return AREF_GROUND;
    case Aref::Common:
      return AREF_COMMON;
    case Aref::Diff:
      return AREF_DIFF;
  }
  return AREF_DIFF;
}

class ComedilibBoard final : public Board {
 public:
  ComedilibBoard(comedi_t* dev, std::string path) : dev_(dev), path_(std::move(path)) {
    // A sample at 0 or maxdata is a clipped reading: a number at the range's
    // end (the runner's clipping check sees it), not NaN in a capture.
    comedi_set_global_oor_behavior(COMEDI_OOR_NUMBER);
  }
  ~ComedilibBoard() override {
    if (calibration_) comedi_cleanup_calibration(calibration_);
    comedi_close(dev_);
  }

  std::string path() const override { return path_; }
  std::string driver_name() const override {
    const char* s = comedi_get_driver_name(dev_);
    return s ? s : "";
  }
  std::string board_name() const override {
    const char* s = comedi_get_board_name(dev_);
    return s ? s : "";
  }
  int find_analog_input() override {
    return comedi_find_subdevice_by_type(dev_, COMEDI_SUBD_AI, 0);
  }

  SubdeviceInfo subdevice(unsigned subdev) override {
    SubdeviceInfo s;
    const int n = comedi_get_n_channels(dev_, subdev);
    const int flags = comedi_get_subdevice_flags(dev_, subdev);
    s.n_channels = n > 0 ? static_cast<unsigned>(n) : 0;
    if (flags >= 0) {
      const auto f = static_cast<unsigned>(flags);
      s.soft_calibrated = (f & SDF_SOFT_CALIBRATED) != 0;
      s.sample_bytes = (f & SDF_LSAMPL) ? sizeof(lsampl_t) : sizeof(sampl_t);
      s.can_stream = (f & SDF_CMD_READ) != 0;
    }
    return s;
  }

  std::vector<Range> ranges(unsigned subdev, unsigned channel) override {
    std::vector<Range> out;
    const int n = comedi_get_n_ranges(dev_, subdev, channel);
    for (int i = 0; i < n; ++i) {
      const comedi_range* r = comedi_get_range(dev_, subdev, channel, static_cast<unsigned>(i));
      if (!r) break;
      out.push_back(Range{r->min, r->max, r->unit == UNIT_volt});
    }
    return out;
  }

  std::uint32_t maxdata(unsigned subdev, unsigned channel) override {
    return comedi_get_maxdata(dev_, subdev, channel);
  }

  std::optional<Polynomial> softcal(unsigned subdev, unsigned channel, unsigned range) override {
    if (!calibration_tried_) {
      calibration_tried_ = true;
      if (char* p = comedi_get_default_calibration_path(dev_)) {
        calibration_ = comedi_parse_calibration_file(p);  // null: no file (not calibrated yet)
        std::free(p);
      }
    }
    if (!calibration_) return std::nullopt;
    comedi_polynomial_t poly{};
    if (comedi_get_softcal_converter(subdev, channel, range, COMEDI_TO_PHYSICAL, calibration_,
                                     &poly) < 0)
      return std::nullopt;
    Polynomial out;
    out.expansion_origin = poly.expansion_origin;
    for (unsigned i = 0; i <= poly.order && i < COMEDI_MAX_NUM_POLYNOMIAL_COEFFICIENTS; ++i)
      out.coefficients.push_back(poly.coefficients[i]);
    return out;
  }

  int command_test(Command& c) override {
    comedi_cmd cmd;
    std::memset(&cmd, 0, sizeof cmd);
    const auto n = static_cast<unsigned>(c.chanlist.size());
    if (comedi_get_cmd_generic_timed(dev_, c.subdevice, &cmd, n, c.scan_period_ns) < 0) return -1;
    fill(cmd, c);
    const int ret = comedi_command_test(dev_, &cmd);
    c.scan_period_ns = cmd.scan_begin_src == TRIG_TIMER ? cmd.scan_begin_arg : 0;
    c.convert_period_ns = cmd.convert_src == TRIG_TIMER ? cmd.convert_arg : 0;
    tested_ = cmd;
    return ret;
  }

  int command(const Command& c) override {
    comedi_cmd cmd = tested_;  // the generic-timed sources the test settled on
    fill(cmd, c);
    cmd.scan_begin_arg = c.scan_period_ns;
    if (cmd.convert_src == TRIG_TIMER) cmd.convert_arg = c.convert_period_ns;
    return comedi_command(dev_, &cmd);
  }

  ReadResult read(std::span<std::uint8_t> buf, double timeout_s) override {
    const int fd = comedi_fileno(dev_);
    pollfd p{fd, POLLIN, 0};
    const int ms = static_cast<int>(std::ceil(std::max(0.0, timeout_s) * 1000.0));
    const int ready = ::poll(&p, 1, ms);
    if (ready < 0) return {ReadResult::Status::Error, 0, errno};
    if (ready == 0) return {ReadResult::Status::Timeout, 0, 0};
    const ssize_t n = ::read(fd, buf.data(), buf.size());
    if (n < 0) return {ReadResult::Status::Error, 0, errno};
    if (n == 0) return {ReadResult::Status::End, 0, 0};
    return {ReadResult::Status::Data, static_cast<std::size_t>(n), 0};
  }

  void cancel(unsigned subdev) override { comedi_cancel(dev_, subdev); }
  int last_error() const override { return comedi_errno(); }
  std::string error_text(int error) const override {
    const char* s = comedi_strerror(error);
    return s ? s : std::strerror(error);
  }
  double to_phys(std::uint32_t raw, const Range& r, std::uint32_t maxdata) const override {
    comedi_range cr{r.min, r.max, static_cast<unsigned>(r.volts ? UNIT_volt : UNIT_none)};
    return comedi_to_phys(raw, &cr, maxdata);
  }
  double to_physical(std::uint32_t raw, const Polynomial& p) const override {
    comedi_polynomial_t poly{};
    poly.expansion_origin = p.expansion_origin;
    poly.order = p.coefficients.empty() ? 0 : static_cast<unsigned>(p.coefficients.size() - 1);
    for (std::size_t i = 0; i < p.coefficients.size() && i < COMEDI_MAX_NUM_POLYNOMIAL_COEFFICIENTS;
         ++i)
      poly.coefficients[i] = p.coefficients[i];
    return comedi_to_physical(raw, &poly);
  }

 private:
  void fill(comedi_cmd& cmd, const Command& c) {
    chanlist_.clear();
    for (const auto& ch : c.chanlist)
      chanlist_.push_back(CR_PACK(ch.channel, ch.range, aref_bits(ch.aref)));
    cmd.subdev = c.subdevice;
    if (c.external_start) {
      // NI E/M series: the PFI line as the trigger source, on its edge.
      cmd.start_src = TRIG_EXT;
      cmd.start_arg = CR_EDGE | NI_EXT_PFI(c.start_pfi) | (c.start_falling ? CR_INVERT : 0u);
    } else {
      cmd.start_src = TRIG_NOW;
      cmd.start_arg = 0;
    }
    cmd.scan_end_src = TRIG_COUNT;
    cmd.scan_end_arg = static_cast<unsigned>(chanlist_.size());
    cmd.stop_src = TRIG_COUNT;
    cmd.stop_arg = c.scans;
    cmd.chanlist = chanlist_.data();
    cmd.chanlist_len = static_cast<unsigned>(chanlist_.size());
  }

  comedi_t* dev_;
  std::string path_;
  comedi_calibration_t* calibration_ = nullptr;
  bool calibration_tried_ = false;
  comedi_cmd tested_{};
  std::vector<unsigned> chanlist_;  // must outlive comedi_command (the kernel copies it then)
};

}  // namespace

std::unique_ptr<Board> open_comedilib_board(const std::string& path) {
  comedi_t* dev = comedi_open(path.c_str());
  if (!dev) {
    const int e = comedi_errno();
    const char* why = comedi_strerror(e);
    throw InstrumentError("comedi://" + path + ": cannot open (" +
                          std::string(why ? why : "unknown error") +
                          "); is the board configured (comedi_config) and readable by you?");
  }
  return std::make_unique<ComedilibBoard>(dev, path);
}

}  // namespace piezo::drivers::comedi
