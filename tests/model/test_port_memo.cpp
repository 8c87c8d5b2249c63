// PortModelMemo (model/port_memo.hpp): a remembered port model is the model a
// solve gives, bit for bit — whatever solver solved it first and whatever it
// solved in between — and any input that differs asks for a solve.
#include "model/port_memo.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <thread>
#include <vector>

#include "model/material.hpp"
#include "model/modal.hpp"
#include "model/tube_model.hpp"
#include "model/work_counters.hpp"

namespace {
using namespace piezo::model;

PiezoMaterialE material(double ye11 = 6.66e10, double nu12 = 0.3333) {
  return to_e_form(to_d_form(IsotropicPiezoParams{ye11, nu12, -210e-12, 2294 * kEps0}));
}

ModalOptions options(double end_mass = 0.0) {
  ModalOptions o;
  o.n_modes = 16;
  o.end_mass_fraction = end_mass;
  return o;
}

// Every number of the two models, as bits.
void expect_same_bits(const ModalPortModel& a, const ModalPortModel& b) {
  auto same = [](double x, double y) { return std::memcmp(&x, &y, sizeof x) == 0; };
  EXPECT_TRUE(same(a.c_clamped, b.c_clamped));
  EXPECT_TRUE(same(a.c_static, b.c_static));
  EXPECT_TRUE(same(a.c_residual, b.c_residual));
  EXPECT_TRUE(same(a.eps_t_over_s, b.eps_t_over_s));
  EXPECT_TRUE(same(a.end_mass_fraction, b.end_mass_fraction));
  EXPECT_EQ(a.converged, b.converged);
  ASSERT_EQ(a.modes.size(), b.modes.size());
  for (std::size_t i = 0; i < a.modes.size(); ++i) {
    EXPECT_TRUE(same(a.modes[i].omega, b.modes[i].omega)) << "mode " << i;
    EXPECT_TRUE(same(a.modes[i].participation, b.modes[i].participation)) << "mode " << i;
    EXPECT_TRUE(same(a.modes[i].kappa, b.modes[i].kappa)) << "mode " << i;
    EXPECT_TRUE(same(a.modes[i].radiation_damping, b.modes[i].radiation_damping)) << "mode " << i;
    EXPECT_EQ(a.modes[i].symmetric, b.modes[i].symmetric);
    EXPECT_EQ(a.modes[i].residual, b.modes[i].residual);
  }
}

TEST(PortModelMemo, RemembersTheSolvedBitsAcrossSolversAndStaysOutOfTheWayOfOtherInputs) {
  auto tube = std::make_shared<const TubeModel>(TubeGeometry{}, MeshOptions{});
  auto memo = std::make_shared<PortModelMemo>(tube);
  ModalSolver first(*tube), second(*tube, first.half_model()), fresh(*tube);
  first.set_memo(memo);
  second.set_memo(memo);

  // Solved by the first solver (after other models, so that its kept factor
  // and mass factor are another material's), then asked of the second one.
  first.port_model(material(6.2e10), options(0.02));
  const ModalPortModel solved = first.port_model(material(), options());
  const long solves = modal_solves();
  const ModalPortModel remembered = second.port_model(material(), options());
  EXPECT_EQ(modal_solves(), solves) << "a remembered model is not solved again";
  EXPECT_EQ(memo->hits(), 1);
  expect_same_bits(remembered, solved);
  expect_same_bits(remembered, fresh.port_model(material(), options()));  // a solver without the memo

  // Another material (one ulp of YE11), end mass, option or check: solved.
  const long before = modal_solves();
  const double ye_next = std::nextafter(6.66e10, 1e11);
  second.port_model(material(ye_next), options());
  second.port_model(material(), options(1e-3));
  ModalOptions more = options();
  more.n_modes = 18;
  second.port_model(material(), more);
  second.set_physical_checks(false);
  second.port_model(material(), options());
  EXPECT_EQ(memo->hits(), 1);
  EXPECT_EQ(modal_solves(), before + 4);

  // A model with its shapes (a ModalResult asked for) is always solved.
  ModalResult sc;
  first.port_model(material(), options(), &sc);
  EXPECT_EQ(memo->hits(), 1);
  EXPECT_FALSE(sc.modes.empty());
}

TEST(PortModelMemo, IsIgnoredByASolverOfAnotherTubeAndKeepsItsCapacity) {
  auto tube = std::make_shared<const TubeModel>(TubeGeometry{}, MeshOptions{});
  TubeGeometry longer;
  longer.length_m *= 1.5;
  const TubeModel other(longer, MeshOptions{});
  auto memo = std::make_shared<PortModelMemo>(tube, 2);
  ModalSolver mine(*tube), theirs(other);
  mine.set_memo(memo);
  theirs.set_memo(memo);  // (a mistake: the memo of another tube)
  const ModalPortModel a = mine.port_model(material(), options());
  const ModalPortModel b = theirs.port_model(material(), options());
  EXPECT_EQ(memo->hits(), 0) << "the longer tube's model must not come from this tube's memo";
  EXPECT_LT(b.modes.front().omega, a.modes.front().omega);
  EXPECT_EQ(memo->size(), 1u);

  // At most `capacity` models; the least recently used one goes first.
  mine.port_model(material(6.0e10), options());
  mine.port_model(material(), options());  // (used again: now the most recent)
  EXPECT_EQ(memo->hits(), 1);
  mine.port_model(material(7.0e10), options());  // 6.0e10's goes
  EXPECT_EQ(memo->size(), 2u);
  const long solves = modal_solves();
  mine.port_model(material(), options());
  EXPECT_EQ(modal_solves(), solves);
  mine.port_model(material(6.0e10), options());
  EXPECT_EQ(modal_solves(), solves + 1);

  EXPECT_THROW(PortModelMemo(nullptr), std::invalid_argument);
  EXPECT_THROW(PortModelMemo(tube, 0), std::invalid_argument);
}

TEST(PortModelMemo, ACapturesCountsAreItsOwnWhateverCameBefore) {
  // Two captures in turn (readers): the second takes the first's model, and
  // its counts are those it would have alone — one modal solve the first
  // time it takes the model, none after — while the solve it saved shows in
  // the memo's own counter.
  auto tube = std::make_shared<const TubeModel>(TubeGeometry{}, MeshOptions{});
  auto memo = std::make_shared<PortModelMemo>(tube);
  const long first_capture = PortModelMemo::new_reader(), second_capture = PortModelMemo::new_reader();
  EXPECT_NE(first_capture, second_capture);
  ModalSolver a(*tube), b(*tube);
  a.set_memo(memo, first_capture);
  b.set_memo(memo, second_capture);
  long solves = modal_solves(), remembered = modal_solves_remembered();
  const ModalPortModel solved = a.port_model(material(), options());
  a.port_model(material(), options());  // (its own model again: no solve)
  EXPECT_EQ(modal_solves(), solves + 1);
  EXPECT_EQ(modal_solves_remembered(), remembered);
  solves = modal_solves();
  expect_same_bits(b.port_model(material(), options()), solved);
  EXPECT_EQ(modal_solves(), solves + 1) << "the second capture's first take counts as its solve";
  EXPECT_EQ(modal_solves_remembered(), remembered + 1) << "… one it did not do";
  b.port_model(material(), options());
  EXPECT_EQ(modal_solves(), solves + 1);
  EXPECT_EQ(memo->hits(), 3);
}

TEST(PortModelMemo, TwoThreadsAskingAtOnceGetTheSameBits) {
  auto tube = std::make_shared<const TubeModel>(TubeGeometry{}, MeshOptions{});
  auto memo = std::make_shared<PortModelMemo>(tube);
  ModalSolver a(*tube), fresh(*tube);
  ModalSolver b(*tube, a.half_model());
  a.set_memo(memo);
  b.set_memo(memo);
  std::vector<ModalPortModel> pa(6), pb(6);
  auto run = [&](ModalSolver& s, std::vector<ModalPortModel>& out) {
    for (int i = 0; i < 6; ++i) out[static_cast<std::size_t>(i)] = s.port_model(material(6.0e10 + 2e9 * (i % 3)), options());
  };
  std::thread t([&] { run(b, pb); });
  run(a, pa);
  t.join();
  for (int i = 0; i < 6; ++i) {
    const ModalPortModel ref = fresh.port_model(material(6.0e10 + 2e9 * (i % 3)), options());
    expect_same_bits(pa[static_cast<std::size_t>(i)], ref);
    expect_same_bits(pb[static_cast<std::size_t>(i)], ref);
  }
  EXPECT_EQ(memo->size(), 3u);
}

}  // namespace
