#pragma once
// A core lent to the output-error fit's two-thread steps (issue 43).
//
// A fit's steps that can use two threads (prefetch's port models, a reduced
// basis's snapshots, the effect scan's tasks, the held-out predictions) run
// on one where the caller keeps every core busy already (OeOptions::threads
// = 1: a batch replay with --jobs > 1). At the end of a batch, though, a
// worker whose siblings have no capture left idles while the last capture
// runs on one core. The batch counts its idle workers (jobs/replay/
// worker_pool.hpp, in memory the worker processes share); with that count
// set here, a step may take a second thread while it is above zero.
//
// The answers do not depend on it: each of those steps gives the same bits on
// one thread or two (an FE model is a function of its key alone; the scan's
// tasks each start from the same state), as `replay --jobs 1` (two threads a
// fit) and `--jobs 2` (one) already show. A step inside a two-thread step
// never borrows (the second solver is the other thread's then).
#include <atomic>
#include <functional>

namespace piezo::update::oe {

// The count of spare cores to read (nullptr, the default: none is ever).
void set_spare_cores(const std::atomic<int>* count);

// Whether a step that can use a second thread may take one now: a core is
// spare and this thread is not inside a two-thread step.
bool may_borrow_core();

// A two-thread step: `other` on a second thread, `mine` on this one, each
// inside the step (no borrowing within), joined before it returns — also
// when `mine` throws (the exception then passes on).
void on_two_threads(const std::function<void()>& other, const std::function<void()>& mine);

// Marks the calling thread as inside a two-thread step while it lives.
class TwoThreadScope {
 public:
  TwoThreadScope();
  ~TwoThreadScope();
  TwoThreadScope(const TwoThreadScope&) = delete;
  TwoThreadScope& operator=(const TwoThreadScope&) = delete;

 private:
  bool was_;
};

}  // namespace piezo::update::oe
