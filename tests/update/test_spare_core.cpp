// The lent core (update/output_error/spare_core.hpp): a step may take a second
// thread only while the shared count says a core is spare, and never from
// inside a two-thread step (whose second solver is the other thread's).
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "update/output_error/spare_core.hpp"

using namespace piezo::update::oe;

TEST(SpareCore, BorrowedOnlyWhileCountedAndNeverInsideATwoThreadStep) {
  EXPECT_FALSE(may_borrow_core());  // no count set: none is ever spare
  std::atomic<int> count{0};
  set_spare_cores(&count);
  EXPECT_FALSE(may_borrow_core());
  count = 1;
  EXPECT_TRUE(may_borrow_core());
  {
    const TwoThreadScope outer;
    EXPECT_FALSE(may_borrow_core());
    {
      const TwoThreadScope inner;
      EXPECT_FALSE(may_borrow_core());
    }
    EXPECT_FALSE(may_borrow_core());  // still inside the outer step
    bool other_thread = false;        // another thread is not inside this one's step
    std::thread t([&] { other_thread = may_borrow_core(); });
    t.join();
    EXPECT_TRUE(other_thread);
  }
  EXPECT_TRUE(may_borrow_core());
  count = 0;
  EXPECT_FALSE(may_borrow_core());
  set_spare_cores(nullptr);
  count = 1;
  EXPECT_FALSE(may_borrow_core());
}
