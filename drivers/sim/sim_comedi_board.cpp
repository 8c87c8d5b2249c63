#include "drivers/sim/sim_comedi_board.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace piezo::drivers::sim {

namespace {
constexpr unsigned kChannels = 4, kBits = 12, kMaxData = (1u << kBits) - 1, kPfiLines = 10;
constexpr unsigned kTimebaseNs = 50, kMinScanNs = 200;
constexpr double kRanges[] = {50.0, 20.0, 10.0, 5.0, 2.0, 1.0, 0.5, 0.2};  // ni_pcimio's 611x table
constexpr unsigned kNumRanges = sizeof kRanges / sizeof kRanges[0];
}  // namespace

SimComediBoard::SimComediBoard(std::shared_ptr<SimBench> bench, std::string path,
                               bool soft_calibrated)
    : bench_(std::move(bench)), path_(std::move(path)), soft_calibrated_(soft_calibrated) {
  if (!bench_) throw std::invalid_argument("SimComediBoard: null bench");
  if (bench_->imperfections().adc_bits != static_cast<int>(kBits))
    throw std::invalid_argument(
        "SimComediBoard: the simulated PCI-6110 digitises with 12 bits; the bench has " +
        std::to_string(bench_->imperfections().adc_bits));
}

comedi::SubdeviceInfo SimComediBoard::subdevice(unsigned subdev) {
  comedi::SubdeviceInfo s;
  if (subdev != 0) return s;
  s.n_channels = kChannels;
  s.soft_calibrated = soft_calibrated_;
  s.sample_bytes = 2;
  s.can_stream = true;
  return s;
}

std::vector<comedi::Range> SimComediBoard::ranges(unsigned subdev, unsigned channel) {
  std::vector<comedi::Range> out;
  if (subdev != 0 || channel >= kChannels) return out;
  for (double r : kRanges) out.push_back({-r, r, true});
  return out;
}

std::uint32_t SimComediBoard::maxdata(unsigned subdev, unsigned channel) {
  return subdev == 0 && channel < kChannels ? kMaxData : 0;
}

std::optional<comedi::Polynomial> SimComediBoard::softcal(unsigned subdev, unsigned channel,
                                                          unsigned range) {
  if (!soft_calibrated_ || subdev != 0 || channel >= kChannels || range >= kNumRanges)
    return std::nullopt;
  const double half = static_cast<double>(kMaxData + 1) / 2.0;  // 2048: code 0
  return comedi::Polynomial{{0.0, kRanges[range] / half}, half};
}

int SimComediBoard::command_test(comedi::Command& c) {
  if (gone_) {
    errno_ = ENODEV;
    return -1;
  }
  if (c.subdevice != 0) {
    errno_ = EINVAL;
    return -1;
  }
  if (!c.external_start) return 1;  // TRIG_NOW: not modelled (see the header)
  int ret = 0;
  if (c.start_pfi >= kPfiLines || c.scans == 0) ret = 3;
  if (c.scan_period_ns < kMinScanNs) {
    c.scan_period_ns = kMinScanNs;
    ret = std::max(ret, 3);
  }
  const unsigned rounded =
      (c.scan_period_ns + kTimebaseNs / 2) / kTimebaseNs * kTimebaseNs;  // TRIG_ROUND_NEAREST
  if (ret == 0 && rounded != c.scan_period_ns) {
    c.scan_period_ns = rounded;
    ret = 4;
  }
  c.convert_period_ns = 0;  // simultaneous sampling
  if (ret != 0) return ret;
  if (c.chanlist.empty() || c.chanlist.size() > kChannels) return 5;
  for (const auto& ch : c.chanlist)
    if (ch.channel >= kChannels || ch.range >= kNumRanges || ch.aref != comedi::Aref::Diff)
      return 5;
  return 0;
}

int SimComediBoard::command(const comedi::Command& c) {
  comedi::Command tested = c;
  if (command_test(tested) != 0 || tested.scan_period_ns != c.scan_period_ns) {
    if (!gone_) errno_ = EINVAL;
    return -1;
  }
  if (c.chanlist.size() != 2) {  // the bench records two signals
    errno_ = EINVAL;
    return -1;
  }
  std::lock_guard lock(bench_->mutex());
  DaqState& d = bench_->daq();
  d.sample_rate_hz = 1e9 / static_cast<double>(c.scan_period_ns);
  d.points = c.scans;
  d.position_s = 0.0;  // the record starts at the trigger
  for (int k = 0; k < 2; ++k)
    d.full_scale_v[k] = 2.0 * kRanges[c.chanlist[static_cast<std::size_t>(k)].range];
  d.aux_trigger = true;
  d.armed = true;
  d.done = false;
  armed_at_ = bench_->acquisitions();
  running_ = true;
  filled_ = false;
  stream_.clear();
  read_pos_ = 0;
  ++commands_;
  return 0;
}

void SimComediBoard::fill_stream() {
  const DaqState& d = bench_->daq();
  const std::size_t n = d.codes[0].size();
  const int word_step = 1 << (16 - kBits);
  stream_.resize(n * 2 * sizeof(std::uint16_t));
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < 2; ++k) {
      const int code = d.codes[k][i] / word_step;  // exact: the bench's words are code · 16
      const auto raw = static_cast<std::uint16_t>(code + static_cast<int>((kMaxData + 1) / 2));
      std::memcpy(stream_.data() + (i * 2 + static_cast<std::size_t>(k)) * 2, &raw, 2);
    }
  shot_ = bench_->acquisitions() - 1;
  filled_ = true;
}

comedi::ReadResult SimComediBoard::read(std::span<std::uint8_t> buf, double) {
  using S = comedi::ReadResult::Status;
  if (gone_) return {S::Error, 0, ENODEV};
  if (!running_ && read_pos_ >= stream_.size()) return {S::End, 0, 0};
  std::lock_guard lock(bench_->mutex());
  if (!filled_) {
    if (bench_->acquisitions() == armed_at_) return {S::Timeout, 0, 0};  // no trigger yet
    fill_stream();
  }
  const FaultPlan& f = bench_->faults();
  const bool fault_here = f.at_shot == shot_;
  using K = FaultPlan::Kind;
  if (fault_here && f.kind == K::ComediNoData) return {S::Timeout, 0, 0};
  const std::size_t third = stream_.size() / 3 / 4 * 4;  // whole scans
  if (fault_here && (f.kind == K::ComediOverrun || f.kind == K::ComediDeviceGone) &&
      read_pos_ >= third) {
    running_ = false;
    if (f.kind == K::ComediDeviceGone) gone_ = true;
    return {S::Error, 0, f.kind == K::ComediOverrun ? EPIPE : ENODEV};
  }
  if (read_pos_ >= stream_.size()) {
    running_ = false;
    return {S::End, 0, 0};
  }
  // At most 4 KiB per read (a page of the kernel's buffer), so the driver reads in pieces.
  std::size_t n = std::min({buf.size(), stream_.size() - read_pos_, std::size_t{4096}});
  if (fault_here && f.kind != K::None && read_pos_ < third) n = std::min(n, third - read_pos_);
  std::memcpy(buf.data(), stream_.data() + read_pos_, n);
  read_pos_ += n;
  if (read_pos_ >= stream_.size()) running_ = false;  // TRIG_COUNT reached
  return {S::Data, n, 0};
}

void SimComediBoard::cancel(unsigned) {
  running_ = false;
  stream_.clear();  // what was not read is gone: a read now sees the end
  read_pos_ = 0;
  filled_ = true;
  ++cancels_;
  std::lock_guard lock(bench_->mutex());
  bench_->daq().armed = false;
}

std::string SimComediBoard::error_text(int error) const { return std::strerror(error); }

}  // namespace piezo::drivers::sim
