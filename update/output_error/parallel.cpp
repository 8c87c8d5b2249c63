// Independent tasks on up to two threads (parallel.hpp).
#include "update/output_error/parallel.hpp"

#include <atomic>
#include <exception>
#include <mutex>

namespace piezo::update::oe {

int in_parallel(Fitter& fitter, const std::vector<std::size_t>& order, const Problem::State& start,
                const Task& task) {
  Problem& prob = fitter.prob;
  int models_elsewhere = 0;  // FE models the fork built
  std::atomic<std::size_t> next{0};
  std::mutex error_mutex;
  std::exception_ptr error;
  auto work = [&](Problem& p, Fitter& f) {
    for (std::size_t k = next++; k < order.size(); k = next++) {
      try {
        p.restore(start);
        task(p, f, order[k]);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
      }
    }
  };
  if (order.size() > 1 && prob.two_threads()) {
    Problem other(prob, prob.second_solver());
    Fitter other_fit = fitter.on(other);
    const int threads = prob.threads();
    prob.set_threads(1);  // (the second solver is the other thread's now; nor does either thread borrow a core)
    on_two_threads([&] { work(other, other_fit); }, [&] { work(prob, fitter); });
    prob.set_threads(threads);
    models_elsewhere += other.evaluations();
  } else {
    work(prob, fitter);
  }
  // And the fit's Problem as the tasks found it (what its own thread's last
  // task left would differ with the thread count).
  prob.restore(start);
  if (error) std::rethrow_exception(error);
  return models_elsewhere;
}

}  // namespace piezo::update::oe
