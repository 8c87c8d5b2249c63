// Problem's FE port models (forward_model.hpp): the small cache keyed by the
// constants' coordinates and the end mass, the second solver on a second
// thread, the fork for another thread, and the port models' tangent that
// spares an FE model per Jacobian column near its anchor.
#include "update/output_error/forward_model.hpp"

#include <algorithm>
#include <cmath>
#include <exception>

namespace piezo::update::oe {

const model::ModalPortModel* Problem::port_of(const Eigen::VectorXd& x, double end_mass) {
  const Key key = key_of(x, end_mass);
  if (Cached* c = cached(key)) return c->port ? &*c->port : nullptr;
  return insert(key, build(solver_, key, armed()));
}

void Problem::prefetch(const std::vector<std::pair<Eigen::VectorXd, double>>& points) {
  std::vector<Key> todo;
  for (const auto& [x, mass] : points) {
    const Key key = key_of(x, mass);
    if (!cached(key) && std::find(todo.begin(), todo.end(), key) == todo.end()) todo.push_back(key);
  }
  if (todo.empty()) return;
  // On the surrogate, an exact Jacobian's columns about a modal solve's
  // point: a basis there instead (its plus-points cost what the columns
  // would), the columns and the run's next iterates from it.
  if (armed() && todo.size() >= 3) {
    const Cached* base = nullptr;
    for (const auto& c : cache_)
      if (c.port && !c.basis && (c.key - todo[0]).cwiseAbs().maxCoeff() <= kSameSource) base = &c;
    bool all_near = base != nullptr;
    for (const auto& k : todo) all_near = all_near && (k - base->key).cwiseAbs().maxCoeff() <= kSameSource;
    if (all_near) {
      const Key centre = base->key;
      bool mass = false;  // (a plus-point in the end mass when the Jacobian has a column in it)
      for (const auto& k : todo) mass = mass || k[4] != centre[4];
      if (Basis b = make_basis(centre, mass, two_threads(), solver_)) {
        local_.emplace_back(centre, b);
        for (const auto& k : todo) {
          Built one;
          try {
            auto p = b->port_model(material_at(k), k[4]);
            if (p.converged) one = {std::move(p), b};
          } catch (const std::exception&) {
          }
          if (one.port) {
            ++evaluations_;
            insert(k, std::move(one));
          } else {
            insert(k, build(solver_, k, true));
          }
        }
        return;
      }
    }
  }
  std::vector<Built> built(todo.size());
  const bool arm = armed();  // (decided once for the batch: its threads count solves as they go)
  if (todo.size() > 1 && two_threads()) {
    model::ModalSolver& second = second_solver();
    // The second thread takes the odd points (one FE model each, equal work).
    on_two_threads([&] { for (std::size_t i = 1; i < todo.size(); i += 2) built[i] = build(second, todo[i], arm); },
                   [&] { for (std::size_t i = 0; i < todo.size(); i += 2) built[i] = build(solver_, todo[i], arm); });
  } else {
    for (std::size_t i = 0; i < todo.size(); ++i) built[i] = build(solver_, todo[i], arm);
  }
  for (std::size_t i = 0; i < todo.size(); ++i) insert(todo[i], std::move(built[i]));
}

Problem::Problem(const Problem& o, model::ModalSolver& solver)
    : solver_(solver), cls_(o.cls_), co_(o.co_), modal_(o.modal_), r1_(o.r1_), fx_(o.fx_), free_(o.free_),
      fs_(o.fs_), band_hz_(o.band_hz_), n_(o.n_), nfft_(o.nfft_), fft_(o.nfft_), kmax_(o.kmax_), decim_(o.decim_), l_(o.l_),
      lv1_(o.lv1_), ly_(o.ly_), spec_(o.spec_), buf_(o.buf_), idx_(o.idx_), dinv_(o.dinv_), columns_(o.columns_),
      reduced_(o.reduced_), local_(o.local_), surrogate_(o.surrogate_), exact_since_(o.exact_since_.load()),
      tangent_(o.tangent_),
      cache_(o.cache_), clock_(o.clock_) {}

model::ModalSolver& Problem::second_solver() {
  // (sharing the first solver's upper half: one model build less a fit)
  if (!solver2_) {
    solver2_ = std::make_unique<model::ModalSolver>(solver_.model(),
                                                    modal_.mirror_symmetry ? solver_.half_model() : nullptr);
    solver2_->set_memo(solver_.memo(), solver_.memo_reader());  // (the same tube's port models)
  }
  return *solver2_;
}

void Problem::set_tangent(const Eigen::VectorXd& x, double h, double mass) {
  tangent_.valid = false;
  const model::ModalPortModel* base = port_of(x, mass);
  if (!base) return;
  const model::ModalPortModel b = *base;
  for (int c = 0; c < 4; ++c) {
    Eigen::VectorXd xp = x;
    xp[c] += h;
    const model::ModalPortModel* p = port_of(xp, mass);
    if (!p || !same_structure(*p, b)) return;
    // The largest relative slope of an active mode's ω or |p| in this constant.
    double slope = 0;
    for (std::size_t i = 0; i < b.modes.size(); ++i) {
      const auto &mb = b.modes[i], &mp = p->modes[i];
      const double pa = std::abs(mb.participation);
      if (!(mb.omega > 0) || pa * pa < kActiveCoupling * mb.omega * mb.omega * b.c_clamped) continue;
      slope = std::max({slope, std::abs(std::abs(mp.participation) - pa) / (pa * h),
                        std::abs(mp.omega - mb.omega) / (mb.omega * h)});
    }
    tangent_.slope[static_cast<std::size_t>(c)] = slope;
    tangent_.plus[static_cast<std::size_t>(c)] = *p;
  }
  tangent_.base = b;
  tangent_.x_ref = x.head<4>();
  tangent_.mass = mass;
  tangent_.h = h;
  tangent_.valid = true;
}

std::shared_ptr<const OePortTangent> Problem::export_tangent() const {
  if (!tangent_.valid) return nullptr;
  auto t = std::make_shared<OePortTangent>();
  t->origin = co_.p0;
  t->x_ref = tangent_.x_ref;
  t->mass = tangent_.mass;
  t->h = tangent_.h;
  t->base = tangent_.base;
  t->plus = tangent_.plus;
  t->slope = tangent_.slope;
  return t;
}

void Problem::adopt_tangent(const OePortTangent& t) {
  tangent_.valid = false;
  const TubeParams &a = t.origin, &b = co_.p0;
  const double r0 = b.y_e11 / a.y_e11, r1 = b.nu12 / a.nu12, r2 = b.d31 / a.d31, r3 = b.eps_t33 / a.eps_t33;
  if (!(t.h > 0) || !(r0 > 0) || !(r1 > 0) || !(r2 > 0) || !(r3 > 0) || !std::isfinite(r0 * r1 * r2 * r3)) return;
  for (const auto& p : t.plus)
    if (!same_structure(p, t.base)) return;
  // Coordinates5::params: YE11, d31 and εT33 as logs of the ratio to the
  // origin (so only shifted), nu12 as ν/ν0 − 1 (shifted and scaled: a unit of
  // this problem's coordinate is ν_b/ν_a of the fit's).
  tangent_.x_ref << t.x_ref[0] - std::log(r0), (1.0 + t.x_ref[1]) / r1 - 1.0, t.x_ref[2] - std::log(r2),
      t.x_ref[3] - std::log(r3);
  tangent_.base = t.base;
  tangent_.plus = t.plus;
  tangent_.slope = t.slope;
  model::ModalPortModel p1 = t.base;
  shift(p1, t.plus[1], r1);  // base + (ν_b/ν_a)·(plus − base): the slope per unit of this coordinate
  tangent_.plus[1] = std::move(p1);
  tangent_.slope[1] = t.slope[1] * r1;
  tangent_.mass = t.mass;
  tangent_.h = t.h;
  tangent_.valid = true;
}

bool Problem::tangent_near(const Eigen::VectorXd& x, double mass) {
  if (!tangent_.valid || mass != tangent_.mass ||
      (x.head<4>() - tangent_.x_ref).cwiseAbs().maxCoeff() > kTangentReach)
    return false;
  const model::ModalPortModel* at = port_of(x, mass);
  if (!at || !same_structure(*at, tangent_.base)) return false;
  model::ModalPortModel q = tangent_.base;
  for (int c = 0; c < 4; ++c) shift(q, tangent_.plus[static_cast<std::size_t>(c)], (x[c] - tangent_.x_ref[c]) / tangent_.h);
  for (std::size_t i = 0; i < q.modes.size(); ++i) {
    const auto &a = at->modes[i], &b = q.modes[i];
    const double pa = std::abs(a.participation);
    if (!(a.omega > 0) || pa * pa < kActiveCoupling * a.omega * a.omega * at->c_clamped) continue;
    if (std::abs(b.omega - a.omega) > kTangentOmegaTolerance * a.omega ||
        std::abs(b.participation - pa) > kTangentTolerance * pa)
      return false;
  }
  return true;
}

std::optional<std::vector<cd>> Problem::tangent_model(const Eigen::VectorXd& anchor,
                                                      const Eigen::VectorXd& x) {
  const model::EffectSet fx = effects_at(x);
  if (!tangent_near(anchor, fx.mass_loading) || effects_at(anchor).mass_loading != fx.mass_loading ||
      (x.head<4>() - anchor.head<4>()).cwiseAbs().maxCoeff() > kTangentReach)
    return std::nullopt;
  // … and only as far as its slopes say the modes move by a few percent:
  // near a veering a participation changes by 6 % per 1e-4 of a constant
  // (refsim-like tube, dielectric loss 0.03), and a screen extrapolated to a
  // 1 % step refused every good step of the loss's run.
  double change = 0;
  for (int c = 0; c < 4; ++c) change += std::abs(x[c] - anchor[c]) * tangent_.slope[static_cast<std::size_t>(c)];
  if (!(change <= kScreenChange)) return std::nullopt;
  const model::ModalPortModel* at = port_of(anchor, fx.mass_loading);
  if (!at || !same_structure(*at, tangent_.base)) return std::nullopt;
  model::ModalPortModel p = *at;
  for (int c = 0; c < 4; ++c) shift(p, tangent_.plus[static_cast<std::size_t>(c)], (x[c] - anchor[c]) / tangent_.h);
  return transfer_of(p, co_.beta(x), co_.eta(x), fx);
}

std::optional<std::vector<cd>> Problem::tangent_transfer(const Eigen::VectorXd& x, int c, double h,
                                                         const model::EffectSet& fx) {
  const model::ModalPortModel* at = port_of(x, fx.mass_loading);
  if (!at || !same_structure(*at, tangent_.base)) return std::nullopt;
  model::ModalPortModel p = *at;
  shift(p, tangent_.plus[static_cast<std::size_t>(c)], h / tangent_.h);
  return transfer_of(p, co_.beta(x), co_.eta(x), fx);
}

bool Problem::same_structure(const model::ModalPortModel& a, const model::ModalPortModel& b) {
  if (a.modes.size() != b.modes.size()) return false;
  for (std::size_t i = 0; i < a.modes.size(); ++i)
    if (a.modes[i].symmetric != b.modes[i].symmetric || a.modes[i].residual != b.modes[i].residual) return false;
  return true;
}

void Problem::shift(model::ModalPortModel& p, const model::ModalPortModel& plus, double k) const {
  const model::ModalPortModel& base = tangent_.base;
  p.c_clamped += k * (plus.c_clamped - base.c_clamped);
  p.c_static += k * (plus.c_static - base.c_static);
  p.c_residual += k * (plus.c_residual - base.c_residual);
  p.eps_t_over_s += k * (plus.eps_t_over_s - base.eps_t_over_s);
  for (std::size_t i = 0; i < p.modes.size(); ++i) {
    auto& m = p.modes[i];
    const auto &mp = plus.modes[i], &mb = base.modes[i];
    m.omega += k * (mp.omega - mb.omega);
    m.kappa += k * (mp.kappa - mb.kappa);
    // p_k = gᵀφ_k: its sign is the eigenvector's, arbitrary per solve.
    m.participation = std::abs(m.participation) + k * (std::abs(mp.participation) - std::abs(mb.participation));
  }
}

Problem::Cached* Problem::cached(const Key& key) {
  for (auto& c : cache_)
    if (c.key == key) {
      if (c.basis && !surrogate_) return nullptr;  // (a surrogate's model: solved again, exactly)
      c.used = ++clock_;
      return &c;
    }
  return nullptr;
}

void Problem::use_reduced(const Eigen::VectorXd& centre, double end_mass) {
  reduced_ = std::make_shared<Reduced>();
  reduced_->centre = key_of(centre, end_mass);
  local_.clear();
  exact_since_ = 0;
}

void Problem::set_surrogate(bool on) {
  if (on && !reduced_) throw std::logic_error("Problem::set_surrogate: use_reduced first");
  surrogate_ = on;
}

model::PiezoMaterialE Problem::material_at(const Key& key) const {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(kParams);
  x.head<4>() = key.head<4>();
  return cls_.e_form(co_.params(x));
}

std::optional<Problem::Basis> Problem::same_source(const Key& key) const {
  for (const auto& c : cache_)
    if (c.port && (c.key - key).cwiseAbs().maxCoeff() <= kSameSource) return c.basis;
  return std::nullopt;
}

std::vector<model::ReducedPort::Point> Problem::basis_points(const Key& centre, bool mass) const {
  // The centre, its plus-points in the four constants and (mass) in the end mass.
  std::vector<model::ReducedPort::Point> points{{material_at(centre), centre[4]}};
  for (int c = 0; c < (mass ? 5 : 4); ++c) {
    Key k = centre;
    k[c] += kReducedStep;
    points.push_back({material_at(k), k[4]});
  }
  return points;
}

std::shared_ptr<const model::ReducedPortSpace> Problem::reduced_space() {
  const std::lock_guard<std::mutex> lock(reduced_->mutex);
  if (!reduced_->space) {
    const auto half = solver_.half_model();  // (built with the fit's first port model)
    try {
      if (half)  // (the bases here are built without error estimates)
        reduced_->space = std::make_shared<const model::ReducedPortSpace>(half, material_at(reduced_->centre), false);
    } catch (const std::exception&) {
    }
  }
  return reduced_->space;
}

Problem::Basis Problem::make_basis(const Key& centre, bool mass, bool two_threads, model::ModalSolver& solver) {
  std::vector<model::ReducedPort::Point> points;
  try {
    points = basis_points(centre, mass);
  } catch (const std::exception&) {
    return nullptr;  // (a plus-point outside the physical domain)
  }
  // The snapshots, the odd ones on the second solver with two_threads.
  std::vector<std::optional<model::PortVectors>> v(points.size());
  auto take = [&](model::ModalSolver& s, std::size_t first, std::size_t stride) {
    for (std::size_t i = first; i < points.size(); i += stride) {
      model::ModalOptions o = modal_;
      o.end_mass_fraction = points[i].end_mass_fraction;
      try {
        v[i] = s.port_vectors(points[i].material, o);
      } catch (const std::exception&) {
        v[i].reset();  // (a snapshot outside the physical domain)
      }
    }
  };
  if (two_threads) {
    model::ModalSolver& second = second_solver();
    on_two_threads([&] { take(second, 1, 2); }, [&] { take(solver_, 0, 2); });
  } else {
    take(solver, 0, 1);
  }
  std::vector<model::PortVectors> snaps;
  for (auto& x : v) {
    if (!x) return nullptr;
    snaps.push_back(std::move(*x));
  }
  model::ModalOptions o = modal_;
  o.end_mass_fraction = centre[4];
  try {
    auto b = model::ReducedPort::build(snaps, points[0].material, o, reduced_space(), false);
    if (b) return std::make_shared<const model::ReducedPort>(std::move(*b));
  } catch (const std::exception&) {
  }
  return nullptr;
}

Problem::Built Problem::reduced_model(model::ModalSolver& solver, const Key& key) {
  if (!reduced_) return {};
  try {
    return reduced_model_at(solver, key, material_at(key));
  } catch (const std::exception&) {
    return {};  // (outside the physical domain: the modal solve says so)
  }
}

Problem::Built Problem::reduced_model_at(model::ModalSolver& solver, const Key& key, const model::PiezoMaterialE& m) {
  const std::shared_ptr<Reduced> rd = reduced_;
  if (const auto same = same_source(key)) {
    if (!*same) return {};  // next to a modal solve's
    try {
      auto port = (*same)->port_model(m, key[4]);
      if (port.converged) return {std::move(port), *same};
    } catch (const std::exception&) {
    }
    return {};
  }
  auto reaches = [&](const Key& centre) {
    return (key.head<4>() - centre.head<4>()).cwiseAbs().maxCoeff() <= kReducedReach &&
           std::abs(key[4] - centre[4]) <= kReducedMassReach;
  };
  // The nearest basis that reaches the key (the optimum's on a tie).
  Basis best;
  double best_d = INFINITY;
  if (reaches(rd->centre)) {
    const auto space = reduced_space();
    {
      const std::lock_guard<std::mutex> lock(rd->mutex);
      if (!rd->tried) {
        rd->tried = true;
        try {
          if (auto b = model::ReducedPort::build(solver, basis_points(rd->centre, false), modal_, space, false))
            rd->basis = std::make_shared<const model::ReducedPort>(std::move(*b));
        } catch (const std::exception&) {
        }
      }
    }
    if (rd->basis) {
      best = rd->basis;
      best_d = (key - rd->centre).cwiseAbs().maxCoeff();
    }
  }
  for (const auto& [centre, b] : local_) {
    const double d = (key - centre).cwiseAbs().maxCoeff();
    if (reaches(centre) && d < best_d) best = b, best_d = d;
  }
  if (best) {
    // No error estimate here (it costs a quarter of a modal solve, the
    // reduced model a sixteenth): the runs end on exact models, and a
    // surrogate within reach of its basis is within 1e-5 of them (tests/
    // model/test_reduced_port.cpp: 5e-2 in the constants, 2e-2 in the mass,
    // past a veering included).
    try {
      auto port = best->port_model(m, key[4]);
      if (port.converged) return {std::move(port), best};
    } catch (const std::exception&) {
    }
  }
  return {};  // none reaches it: a modal solve (a basis about it if a Jacobian follows: prefetch)
}

Problem::Built Problem::build(model::ModalSolver& solver, const Key& key, bool armed) {
  ++evaluations_;
  if (armed)
    if (Built r = reduced_model(solver, key); r.port) return r;
  try {
    model::ModalOptions mo = modal_;
    mo.end_mass_fraction = key[4];
    auto port = solver.port_model(material_at(key), mo);
    if (surrogate_) ++exact_since_;  // (atomic: prefetch's two threads)
    if (port.converged) return {std::move(port), nullptr};
  } catch (const std::exception&) {
  }
  return {};
}

const model::ModalPortModel* Problem::insert(const Key& key, Built built) {
  Cached* slot = nullptr;
  for (auto& c : cache_)
    if (c.key == key) slot = &c;  // (a surrogate's model, solved again exactly)
  if (slot) {
  } else if (cache_.size() < kCache) {
    slot = &cache_.emplace_back();
  } else {
    slot = &*std::min_element(cache_.begin(), cache_.end(),
                              [](const Cached& a, const Cached& b) { return a.used < b.used; });
  }
  slot->key = key;
  slot->port = std::move(built.port);
  slot->basis = std::move(built.basis);
  slot->used = ++clock_;
  return slot->port ? &*slot->port : nullptr;
}

}  // namespace piezo::update::oe
