#include "model/port_memo.hpp"

#include <atomic>
#include <bit>
#include <stdexcept>

#include "model/modal.hpp"
#include "model/work_counters.hpp"

namespace piezo::model {

PortModelMemo::PortModelMemo(std::shared_ptr<const TubeModel> tube, std::size_t capacity)
    : tube_(std::move(tube)), capacity_(capacity) {
  if (!tube_) throw std::invalid_argument("PortModelMemo: no tube");
  if (capacity_ == 0) throw std::invalid_argument("PortModelMemo: capacity must be at least 1");
}

PortModelMemo::Key PortModelMemo::key_of(const PiezoMaterialE& m, const ModalOptions& o, bool physical_checks) {
  auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v); };
  auto word = [](long long v) { return static_cast<std::uint64_t>(v); };
  return {bits(m.c_e11),
          bits(m.c_e12),
          bits(m.c_e13),
          bits(m.c_e33),
          bits(m.c_e44),
          bits(m.e31),
          bits(m.e33),
          bits(m.e15),
          bits(m.eps_s11),
          bits(m.eps_s33),
          word(o.n_modes),
          bits(o.shift_hz),
          word(o.ncv),
          bits(o.tolerance),
          word(o.max_iterations),
          bits(o.active_coupling),
          bits(o.active_coupling_open),
          bits(o.end_mass_fraction),
          word(o.mirror_symmetry ? 1 : 0),
          bits(o.outer_surface_impedance),
          word(physical_checks ? 1 : 0)};
}

std::size_t PortModelMemo::KeyHash::operator()(const Key& k) const {
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a over the words
  for (std::uint64_t w : k) {
    h ^= w;
    h *= 1099511628211ull;
  }
  return static_cast<std::size_t>(h ^ (h >> 32));
}

long PortModelMemo::new_reader() {
  static std::atomic<long> next{0};
  return ++next;
}

std::optional<ModalPortModel> PortModelMemo::find(const PiezoMaterialE& material, const ModalOptions& options,
                                                  bool physical_checks, long reader) {
  const Key key = key_of(material, options, physical_checks);
  const std::lock_guard<std::mutex> lock(mutex_);
  const auto it = index_.find(key);
  if (it == index_.end()) return std::nullopt;
  lru_.splice(lru_.begin(), lru_, it->second);
  ++hits_;
  Entry& e = *it->second;
  if (e.reader != reader) {  // another reader's: this reader's first take counts as its solve
    e.reader = reader;
    g_modal_solves.fetch_add(1, std::memory_order_relaxed);
    g_modal_solves_remembered.fetch_add(1, std::memory_order_relaxed);
  }
  return e.port;
}

void PortModelMemo::insert(const PiezoMaterialE& material, const ModalOptions& options, bool physical_checks,
                           const ModalPortModel& port, long reader) {
  const Key key = key_of(material, options, physical_checks);
  const std::lock_guard<std::mutex> lock(mutex_);
  if (const auto it = index_.find(key); it != index_.end()) {  // (another thread solved it meanwhile: the same bits)
    lru_.splice(lru_.begin(), lru_, it->second);
    it->second->reader = reader;
    return;
  }
  lru_.push_front(Entry{key, port, reader});
  index_.emplace(key, lru_.begin());
  if (lru_.size() > capacity_) {
    index_.erase(lru_.back().key);
    lru_.pop_back();
  }
}

std::size_t PortModelMemo::size() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return lru_.size();
}

long PortModelMemo::hits() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return hits_;
}

}  // namespace piezo::model
