// The GUI's calibration prompt logic (jobs/operator_prompt.hpp), without a
// window: a worker thread asks and waits, the "frame loop" (this test) sees
// the question and answers; a cancel flag or close() releases the worker.
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <thread>

#include "jobs/operator_prompt.hpp"

namespace {
using namespace std::chrono_literals;
using piezo::jobs::OperatorPrompt;

std::optional<std::string> wait_question(const OperatorPrompt& p) {
  for (int i = 0; i < 200; ++i) {
    if (auto q = p.question()) return q;
    std::this_thread::sleep_for(5ms);
  }
  return std::nullopt;
}

TEST(OperatorPrompt, WorkerWaitsForTheAnswer) {
  OperatorPrompt p;
  EXPECT_FALSE(p.question());
  p.answer(true);  // nothing pending: ignored
  auto yes = std::async(std::launch::async, [&] { return p.ask("connect the OPEN standard"); });
  ASSERT_EQ(wait_question(p), "connect the OPEN standard");
  EXPECT_EQ(yes.wait_for(50ms), std::future_status::timeout);  // still waiting for the person
  p.answer(true);
  EXPECT_TRUE(yes.get());
  EXPECT_FALSE(p.question());
  auto no = std::async(std::launch::async, [&] { return p.ask("connect the SHORT standard"); });
  ASSERT_TRUE(wait_question(p));
  p.answer(false);
  EXPECT_FALSE(no.get());
}

TEST(OperatorPrompt, CancelAndCloseReleaseTheWorker) {
  OperatorPrompt p;
  std::atomic<bool> cancel{false};
  auto a =
      std::async(std::launch::async, [&] { return p.ask("connect the LOAD standard", &cancel); });
  ASSERT_TRUE(wait_question(p));
  cancel = true;
  EXPECT_FALSE(a.get());
  auto b = std::async(std::launch::async, [&] { return p.ask("again"); });
  ASSERT_TRUE(wait_question(p));
  p.close();
  EXPECT_FALSE(b.get());
  EXPECT_FALSE(p.ask("after close"));  // declined at once
}

}  // namespace
