// The replay's worker pool (jobs/replay/worker_pool.hpp) on its own: every
// task's outcome comes back once; a worker that crashes or overruns the
// timeout costs its task only (reported lost with its last stage), and the
// tasks after it are still done by a new worker.
#include <gtest/gtest.h>

#include <atomic>
#include <csignal>
#include <map>
#include <thread>

#include "jobs/replay/worker_pool.hpp"

using namespace piezo::jobs::replay;

TEST(WorkerPool, OutcomesComeBackAndACrashOrAHangCostsItsTaskOnly) {
  std::map<std::size_t, std::string> done;
  std::map<std::size_t, LostTask> lost;
  WorkerPoolCallbacks cb;
  cb.work = [](std::size_t i, const auto& stage) -> std::string {
    stage("working", "task " + std::to_string(i));
    if (i == 2) std::raise(SIGKILL);                                        // a crash inside a library
    if (i == 4) std::this_thread::sleep_for(std::chrono::seconds(30));      // a hang
    return "outcome " + std::to_string(i * i);
  };
  cb.done = [&](std::size_t i, const std::string& o) { EXPECT_TRUE(done.emplace(i, o).second) << i; };
  cb.lost = [&](const LostTask& t) { EXPECT_TRUE(lost.emplace(t.task, t).second) << t.task; };
  std::atomic<bool> cancel{false};
  WorkerPool pool({7, 2, 1.0}, cb, cancel);  // 1 s timeout: the hang is killed
  pool.run();
  ASSERT_EQ(done.size(), 5u);
  for (std::size_t i : {0u, 1u, 3u, 5u, 6u}) EXPECT_EQ(done[i], "outcome " + std::to_string(i * i)) << i;
  ASSERT_EQ(lost.size(), 2u);
  EXPECT_EQ(lost[2].kind, "crashed");
  EXPECT_NE(lost[2].how.find("SIGKILL"), std::string::npos) << lost[2].how;
  EXPECT_EQ(lost[2].stage, "working");
  EXPECT_EQ(lost[2].detail, "task 2");
  EXPECT_EQ(lost[4].kind, "hung");
  EXPECT_EQ(lost[4].detail, "task 4");
  EXPECT_GE(lost[4].elapsed_s, 1.0);
}

TEST(WorkerPool, CancelStopsWithoutReportingWhatIsUnderWay) {
  std::atomic<bool> cancel{true};
  int reported = 0;
  WorkerPoolCallbacks cb;
  cb.work = [](std::size_t, const auto&) -> std::string { return "x"; };
  cb.done = [&](std::size_t, const std::string&) { ++reported; };
  cb.lost = [&](const LostTask&) { ++reported; };
  WorkerPool pool({3, 2, 60.0}, cb, cancel);
  pool.run();
  EXPECT_EQ(reported, 0);
}

// The count of spare cores the workers share with the batch (spare_cores()):
// 0 while tasks remain to be handed out, then the number of workers idle
// with none left — what lets the last capture's fit borrow a core.
TEST(WorkerPool, SpareCoresCountTheIdleWorkersOnceNoTaskIsLeft) {
  std::map<std::size_t, std::string> done;
  const std::atomic<int>* spare = nullptr;  // (set before run() forks the workers)
  WorkerPoolCallbacks cb;
  cb.work = [&spare](std::size_t i, const auto&) -> std::string {
    if (!spare) return "no count";
    if (i != 1) return std::to_string(spare->load());  // task 0 starts while 1 and 2 remain
    // The long task (the second worker's from the start): tasks 0 and 2 go to
    // the other worker, which then idles with none left.
    for (int k = 0; k < 4000 && spare->load() == 0; ++k) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    return std::to_string(spare->load());
  };
  cb.done = [&](std::size_t i, const std::string& o) { done.emplace(i, o); };
  cb.lost = [](const LostTask& t) { ADD_FAILURE() << "task " << t.task << " lost: " << t.kind; };
  std::atomic<bool> cancel{false};
  WorkerPool pool({3, 2, 60.0}, cb, cancel);
  spare = pool.spare_cores();
  ASSERT_NE(spare, nullptr);
  EXPECT_EQ(spare->load(), 0);
  pool.run();
  ASSERT_EQ(done.size(), 3u);
  EXPECT_EQ(done[0], "0");      // tasks still to hand out: none lent
  EXPECT_EQ(done[1], "1");      // the other worker idles with none left: one spare core
  EXPECT_EQ(spare->load(), 0);  // the batch is over: none lent
}

// Fewer tasks than jobs: the jobs no worker is started for are spare from the
// first task on (one capture with --jobs 2 borrows the second core at once).
TEST(WorkerPool, JobsBeyondTheTasksAreSpareFromTheStart) {
  std::map<std::size_t, std::string> done;
  const std::atomic<int>* spare = nullptr;
  WorkerPoolCallbacks cb;
  cb.work = [&spare](std::size_t, const auto&) -> std::string { return spare ? std::to_string(spare->load()) : "no count"; };
  cb.done = [&](std::size_t i, const std::string& o) { done.emplace(i, o); };
  cb.lost = [](const LostTask& t) { ADD_FAILURE() << "task " << t.task << " lost: " << t.kind; };
  std::atomic<bool> cancel{false};
  WorkerPool one({1, 2, 60.0}, cb, cancel);
  spare = one.spare_cores();
  ASSERT_NE(spare, nullptr);
  one.run();
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0], "1");  // one worker for two jobs: one core lent
  EXPECT_EQ(spare->load(), 0);
  done.clear();
  WorkerPool four({2, 4, 60.0}, cb, cancel);
  spare = four.spare_cores();
  four.run();
  ASSERT_EQ(done.size(), 2u);
  EXPECT_GE(std::stoi(done[0]), 2);  // two workers for four jobs: at least two spare
  EXPECT_GE(std::stoi(done[1]), 2);
}
