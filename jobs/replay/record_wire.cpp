#include "jobs/replay/record_wire.hpp"

#include <cstring>
#include <stdexcept>

namespace piezo::jobs::replay {

namespace {

constexpr std::uint64_t kMaxFrame = std::uint64_t(1) << 32;  // 4 GiB: no outcome is near it

class Writer {
 public:
  template <class T>
  void pod(const T& v) {
    out_.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void str(std::string_view s) {
    pod(static_cast<std::uint64_t>(s.size()));
    out_.append(s.data(), s.size());
  }
  void opt_issue(const std::optional<WireIssue>& i) {
    pod(static_cast<std::uint8_t>(i ? 1 : 0));
    if (i) str(i->path), str(i->kind), str(i->message);
  }
  std::string take() { return std::move(out_); }

 private:
  std::string out_;
};

class Reader {
 public:
  explicit Reader(std::string_view in) : in_(in) {}
  template <class T>
  T pod() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, in_.data() + pos_, sizeof v);
    pos_ += sizeof v;
    return v;
  }
  std::string str() {
    const auto n = pod<std::uint64_t>();
    need(n);
    std::string s(in_.substr(pos_, n));
    pos_ += n;
    return s;
  }
  std::optional<WireIssue> opt_issue() {
    if (!pod<std::uint8_t>()) return std::nullopt;
    WireIssue i;
    i.path = str();
    i.kind = str();
    i.message = str();
    return i;
  }
  bool done() const { return pos_ == in_.size(); }

 private:
  void need(std::uint64_t n) const {
    if (n > in_.size() - pos_) throw std::runtime_error("replay worker: truncated outcome");
  }
  std::string_view in_;
  std::size_t pos_ = 0;
};

}  // namespace

std::string encode_outcome(const Outcome& o) {
  Writer w;
  w.pod(static_cast<std::uint8_t>(o.skipped));
  w.pod(static_cast<std::uint8_t>(o.cancelled));
  w.str(o.key);
  const auto& r = o.record;
  w.str(r.key), w.str(r.input_path), w.str(r.sha256), w.str(r.status), w.str(r.result_json);
  w.pod(r.elapsed_s);
  w.str(r.replayed_utc);
  w.pod(static_cast<std::uint64_t>(r.curves.size()));
  for (const auto& c : r.curves) {
    w.str(c.label);
    w.pod(static_cast<std::uint64_t>(c.f_hz.size()));
    for (double f : c.f_hz) w.pod(f);
    w.pod(static_cast<std::uint64_t>(c.z_ohm.size()));
    for (const auto& z : c.z_ohm) w.pod(z.real()), w.pod(z.imag());
  }
  w.opt_issue(o.issue);
  w.opt_issue(o.report_issue);
  return w.take();
}

Outcome decode_outcome(std::string_view payload) {
  Reader rd(payload);
  Outcome o;
  o.skipped = rd.pod<std::uint8_t>() != 0;
  o.cancelled = rd.pod<std::uint8_t>() != 0;
  o.key = rd.str();
  auto& r = o.record;
  r.key = rd.str(), r.input_path = rd.str(), r.sha256 = rd.str(), r.status = rd.str();
  r.result_json = rd.str();
  r.elapsed_s = rd.pod<double>();
  r.replayed_utc = rd.str();
  const auto nc = rd.pod<std::uint64_t>();
  for (std::uint64_t i = 0; i < nc; ++i) {
    acq::StoredCurve c;
    c.label = rd.str();
    const auto nf = rd.pod<std::uint64_t>();
    for (std::uint64_t k = 0; k < nf; ++k) c.f_hz.push_back(rd.pod<double>());
    const auto nz = rd.pod<std::uint64_t>();
    for (std::uint64_t k = 0; k < nz; ++k) {
      const double re = rd.pod<double>();
      c.z_ohm.emplace_back(re, rd.pod<double>());
    }
    r.curves.push_back(std::move(c));
  }
  o.issue = rd.opt_issue();
  o.report_issue = rd.opt_issue();
  if (!rd.done()) throw std::runtime_error("replay worker: trailing bytes after the outcome");
  return o;
}

std::string frame(char kind, std::string_view payload) {
  Writer w;
  w.pod(kind);
  w.str(payload);
  return w.take();
}

bool next_frame(std::string& buf, char& kind, std::string& payload) {
  constexpr std::size_t head = 1 + sizeof(std::uint64_t);
  if (buf.size() < head) return false;
  std::uint64_t n;
  std::memcpy(&n, buf.data() + 1, sizeof n);
  if (n > kMaxFrame) throw std::runtime_error("replay worker: frame of " + std::to_string(n) + " bytes");
  if (buf.size() - head < n) return false;
  kind = buf[0];
  payload.assign(buf, head, n);
  buf.erase(0, head + n);
  return true;
}

}  // namespace piezo::jobs::replay
