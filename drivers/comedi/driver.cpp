#include "drivers/comedi/driver.hpp"

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "drivers/scpi_client.hpp"

namespace piezo::drivers::comedi {

namespace {
std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}
const char* kWho = "comedi::Driver::";
}  // namespace

Driver::Driver(std::unique_ptr<Board> board, const Address& address)
    : board_(std::move(board)), address_(address) {
  if (!board_) throw std::invalid_argument(std::string(kWho) + "Driver: null board");
  const int sd = board_->find_analog_input();
  if (sd < 0) throw InstrumentError(who() + ": no analog-input subdevice");
  subdev_ = static_cast<unsigned>(sd);
  info_ = board_->subdevice(subdev_);
  if (!info_.can_stream)
    throw InstrumentError(who() + ": the analog input (subdevice " + std::to_string(subdev_) +
                          ") cannot stream (no SDF_CMD_READ)");
  for (int k = 0; k < 2; ++k) {
    if (address_.channels[k] >= info_.n_channels)
      throw InstrumentError(who() + ": channel " + std::to_string(address_.channels[k]) + " for v" +
                            std::to_string(k + 1) + ", but the analog input has " +
                            std::to_string(info_.n_channels) + " channels");
    ch_[k].channel = address_.channels[k];
    ch_[k].maxdata = board_->maxdata(subdev_, ch_[k].channel);
    if (ch_[k].maxdata == 0)
      throw InstrumentError(who() + ": maxdata 0 on channel " + std::to_string(ch_[k].channel));
  }
}

Driver::~Driver() {
  if (running_) board_->cancel(subdev_);
}

std::string Driver::who() const {
  const std::string b = board_->board_name();
  return address_.to_string().substr(0, address_.to_string().find('?')) +
         (b.empty() ? "" : " (" + b + ")");
}

std::string Driver::identity() const {
  return "COMEDI," + board_->board_name() + "," + board_->path() + "," + board_->driver_name();
}

std::string Driver::conversion(int ch) const {
  const Channel& c = ch_[ch];
  if (c.softcal) return "softcal polynomial";
  return "comedi_to_phys over [" + num(c.r.min) + ", " + num(c.r.max) + "] V";
}

void Driver::configure(const DaqConfig& c) {
  const std::string w = std::string(kWho) + "configure: ";
  if (!(c.sample_rate_hz > 0) || !std::isfinite(c.sample_rate_hz))
    throw std::invalid_argument(w + "sample rate must be positive");
  if (c.record_length < 2) throw std::invalid_argument(w + "record length must be >= 2");
  if (c.pretrigger_samples != 0)
    throw std::invalid_argument(
        w + "a Comedi command starts at its trigger: no samples before it (pretrigger " +
        std::to_string(c.pretrigger_samples) + "; use 0)");
  if (c.coupling != Coupling::Dc1M)
    throw std::invalid_argument(w + "the driver sets no coupling: DC only (the board's default)");
  if (c.external_trigger != address_.external_trigger)
    throw std::invalid_argument(
        w + (c.external_trigger ? "the plan triggers on the AWG's marker but the address says "
                                  "trigger=software"
                                : "the plan starts by software but the address names a PFI "
                                  "trigger"));
  const double period = 1e9 / c.sample_rate_hz;
  if (!(period >= 1.0 && period <= 4e9))
    throw std::invalid_argument(w + "sample rate " + num(c.sample_rate_hz) +
                                " S/s: the scan period must be 1 ns..4 s");

  if (running_) {  // the previous shot's command (a fault left it running)
    board_->cancel(subdev_);
    running_ = false;
  }
  Channel next[2] = {ch_[0], ch_[1]};
  for (int k = 0; k < 2; ++k) {
    const auto table = board_->ranges(subdev_, next[k].channel);
    // The smallest bipolar range in volts that holds ±range_v.
    std::optional<unsigned> best;
    for (unsigned i = 0; i < table.size(); ++i) {
      const Range& r = table[i];
      if (!r.volts || r.min > -c.range_v[k] || r.max < c.range_v[k]) continue;
      if (!best || (r.max - r.min) < (table[*best].max - table[*best].min)) best = i;
    }
    if (!best) {
      std::string offered;
      for (const auto& r : table)
        if (r.volts) {
          if (!offered.empty()) offered.append(", ");
          offered.append("[").append(num(r.min)).append(", ").append(num(r.max)).append("]");
        }
      throw std::invalid_argument(w + "channel " + std::to_string(next[k].channel) + " (v" +
                                  std::to_string(k + 1) + "): no range holds ±" +
                                  num(c.range_v[k]) + " V (the board offers " + offered + " V)");
    }
    next[k].range = *best;
    next[k].r = table[*best];
    next[k].softcal =
        info_.soft_calibrated ? board_->softcal(subdev_, next[k].channel, *best) : std::nullopt;
  }

  Command cmd;
  cmd.subdevice = subdev_;
  cmd.external_start = address_.external_trigger;
  cmd.start_pfi = address_.pfi;
  cmd.start_falling = address_.falling;
  cmd.scan_period_ns = static_cast<unsigned>(std::lround(period));
  cmd.scans = static_cast<unsigned>(c.record_length);
  for (int k = 0; k < 2; ++k)
    cmd.chanlist.push_back({next[k].channel, next[k].range, address_.aref});
  // comedi_command_test fixes arguments (3) and rounds timers (4): test
  // again until it accepts the command or refuses it outright.
  int ret = 0;
  for (int pass = 0; pass < 3; ++pass) {
    ret = board_->command_test(cmd);
    if (ret != 3 && ret != 4) break;
  }
  if (ret != 0) {
    static const char* stage[] = {"",
                                  "a trigger source is not supported",
                                  "the trigger sources do not go together",
                                  "an argument is out of range",
                                  "the timer cannot be rounded",
                                  "the channel list is not possible"};
    std::string why = ret < 0    ? board_->error_text(board_->last_error())
                      : ret <= 5 ? stage[ret]
                                 : "stage " + std::to_string(ret);
    throw InstrumentError(who() + ": comedi_command_test refused the acquisition (" +
                          (address_.external_trigger ? "start on PFI" + std::to_string(address_.pfi)
                                                     : std::string("software start")) +
                          ", " + std::to_string(cmd.scans) + " scans of 2 channels every " +
                          std::to_string(cmd.scan_period_ns) + " ns): " + why);
  }
  if (cmd.scans != c.record_length)
    throw InstrumentError(who() + ": the board would record " + std::to_string(cmd.scans) +
                          " scans, not " + std::to_string(c.record_length));
  ch_[0] = next[0];
  ch_[1] = next[1];
  cmd_ = cmd;
  configured_ = true;
}

void Driver::arm() {
  if (!configured_) throw std::logic_error(std::string(kWho) + "arm: configure() first");
  if (running_) {
    board_->cancel(subdev_);
    running_ = false;
  }
  if (board_->command(cmd_) < 0) {
    const int e = board_->last_error();
    throw InstrumentError(who() + ": comedi_command failed: " + board_->error_text(e) +
                          (e == ENODEV ? " (device gone)" : ""));
  }
  running_ = true;
}

double Driver::to_volts(const Channel& ch, std::uint32_t raw) const {
  return ch.softcal ? board_->to_physical(raw, *ch.softcal)
                    : board_->to_phys(raw, ch.r, ch.maxdata);
}

DaqRecord Driver::fetch(double timeout_s) {
  if (!configured_ || !running_)
    throw std::logic_error(std::string(kWho) + "fetch: configure() and arm() first");
  const std::size_t scans = cmd_.scans, bytes_per_scan = 2 * info_.sample_bytes;
  std::vector<std::uint8_t> buf(scans * bytes_per_scan);
  std::size_t got = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  auto progress = [&] {
    return std::to_string(got / bytes_per_scan) + " of " + std::to_string(scans) + " scans";
  };
  auto fail = [&](const std::string& what) {
    board_->cancel(subdev_);
    running_ = false;
    throw InstrumentError(who() + ": " + what);
  };
  while (got < buf.size()) {
    const double left =
        std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    const ReadResult r = board_->read(std::span<std::uint8_t>(buf.data() + got, buf.size() - got),
                                      std::max(0.0, left));
    using S = ReadResult::Status;
    if (r.status == S::Data) {
      got += r.bytes;
      continue;
    }
    if (r.status == S::Timeout)
      fail("no samples for " + num(timeout_s) + " s after " + progress() +
           (got == 0 && address_.external_trigger
                ? " (no trigger on PFI" + std::to_string(address_.pfi) +
                      "? is the AWG's marker wired to it?)"
                : ""));
    if (r.status == S::End) fail("the acquisition ended after " + progress());
    if (r.error == EPIPE)
      fail("buffer overrun after " + progress() +
           " (EPIPE: the board's buffer overflowed before it was read; lower the rate or enlarge "
           "the "
           "buffer with comedi_config --read-buffer)");
    if (r.error == ENODEV)
      fail("device gone after " + progress() + " (ENODEV: unplugged or driver unloaded)");
    fail("read failed after " + progress() + ": " + board_->error_text(r.error));
  }
  // TRIG_COUNT: the command ended with the last scan, but the kernel keeps the
  // subdevice busy until a read() sees the end; comedi_cancel releases it, so
  // the next shot's comedi_command does not meet EBUSY.
  board_->cancel(subdev_);
  running_ = false;

  DaqRecord rec;
  rec.v1.resize(scans);
  rec.v2.resize(scans);
  for (std::size_t i = 0; i < scans; ++i) {
    for (int k = 0; k < 2; ++k) {
      const std::uint8_t* p =
          buf.data() + i * bytes_per_scan + static_cast<std::size_t>(k) * info_.sample_bytes;
      std::uint32_t raw = 0;
      if (info_.sample_bytes == 2) {
        std::uint16_t s;
        std::memcpy(&s, p, 2);  // host order, as read() delivers sampl_t
        raw = s;
      } else {
        std::memcpy(&raw, p, 4);
      }
      (k == 0 ? rec.v1 : rec.v2)[i] = to_volts(ch_[k], raw);
    }
  }
  rec.sample_rate_hz = 1e9 / static_cast<double>(cmd_.scan_period_ns);
  rec.pretrigger_samples = 0;
  for (int k = 0; k < 2; ++k) rec.range_v[k] = std::min(-ch_[k].r.min, ch_[k].r.max);
  return rec;
}

}  // namespace piezo::drivers::comedi
