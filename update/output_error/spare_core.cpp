// The lent core (spare_core.hpp).
#include "update/output_error/spare_core.hpp"

#include <thread>

namespace piezo::update::oe {

namespace {
std::atomic<const std::atomic<int>*> g_spare{nullptr};
thread_local bool t_two_threads = false;
}  // namespace

void set_spare_cores(const std::atomic<int>* count) { g_spare.store(count, std::memory_order_release); }

bool may_borrow_core() {
  if (t_two_threads) return false;
  const std::atomic<int>* c = g_spare.load(std::memory_order_acquire);
  return c && c->load(std::memory_order_relaxed) > 0;
}

void on_two_threads(const std::function<void()>& other, const std::function<void()>& mine) {
  std::thread t([&] {
    const TwoThreadScope inside;
    other();
  });
  try {
    const TwoThreadScope inside;
    mine();
  } catch (...) {
    t.join();
    throw;
  }
  t.join();
}

TwoThreadScope::TwoThreadScope() : was_(t_two_threads) { t_two_threads = true; }
TwoThreadScope::~TwoThreadScope() { t_two_threads = was_; }

}  // namespace piezo::update::oe
