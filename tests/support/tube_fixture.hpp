#pragma once
// Test support: one default-mesh tube model and its modal solver, built once
// per test suite (assembly and symbolic factorisation are the slow part).
#include <gtest/gtest.h>

#include <memory>

#include "model/modal.hpp"
#include "model/tube_model.hpp"

namespace piezo::test {

class TubeFixture : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    tube_ = std::make_unique<model::TubeModel>(model::TubeGeometry{});
    solver_ = std::make_unique<model::ModalSolver>(*tube_);
  }
  static void TearDownTestSuite() {
    solver_.reset();
    tube_.reset();
  }
  static inline std::unique_ptr<model::TubeModel> tube_;
  static inline std::unique_ptr<model::ModalSolver> solver_;
};

}  // namespace piezo::test
