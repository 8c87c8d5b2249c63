#pragma once
// The forward model of the output-error fit (update/output_error.hpp): the
// coordinates θ relative to the nominal constants (Coordinates5) and Problem,
// the filtered, decimated output error L ∗ (v̂2 − v2) of one θ, with its FE
// port models' cache and their tangent. Problem's residuals, spectra and
// noise propagation are in forward_model.cpp; the cache, the second solver
// and the tangent in port_cache.cpp. Internal to update/output_error/.
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <tuple>
#include <utility>
#include <vector>

#include "dsp/decimated_inverse.hpp"
#include "dsp/fft.hpp"
#include "model/effects.hpp"
#include "model/modal.hpp"
#include "model/reduced_port.hpp"
#include "update/output_error.hpp"
#include "update/output_error/common.hpp"
#include "update/output_error/shot_average.hpp"
#include "update/output_error/spare_core.hpp"
#include "update/residual_regions.hpp"

namespace piezo::update {

// The baseline columns a problem keeps (Problem::kept_column), shared by its
// forks and, through predict_output_error's `shared`, by the predictions on
// one held-out record: the first problem that joins fixes the shape (record
// length, rate, padding, band, decimation) the others must have.
struct OeRecordShare {
  using ColumnKey = std::tuple<int, int, double>;
  std::mutex mutex;
  std::optional<std::array<double, 5>> shape;
  std::map<ColumnKey, Eigen::VectorXd> columns;
  // The record's filtered spectra (Problem's constructor: its three forward
  // FFTs of the padded record and the low-pass), made by the first problem
  // that joins and copied by the others whose record and shape are the same.
  struct Spectra {
    std::array<double, 5> shape{};
    std::vector<double> v1, v2;  // the record they are of (compared, not trusted)
    std::vector<std::complex<double>> l, lv1, ly;
    std::shared_ptr<const dsp::DecimatedInverse> dinv;  // (copied: its buffer is per problem)
  };
  std::shared_ptr<const Spectra> spectra;
  // The spectrum of a zero record (Problem::spectrum_of), made once by
  // whichever problem sharing the columns needs it first.
  std::once_flag zero_once;
  std::vector<std::complex<double>> zero_bins;
};

}  // namespace piezo::update

namespace piezo::update::oe {

// The parameter vector θ relative to the nominal constants.
struct Coordinates5 {
  TubeParams p0;
  double beta0 = 1e-7;  // the loss at x[4] = 0: β (rayleigh) or η = 1/Qm (complex constants)
  OeDamping damping = OeDamping::rayleigh;
  TubeParams params(const Eigen::VectorXd& x) const {
    TubeParams p = p0;
    p.y_e11 = p0.y_e11 * std::exp(x[0]);
    p.nu12 = p0.nu12 * (1.0 + x[1]);
    p.d31 = p0.d31 * std::exp(x[2]);
    p.eps_t33 = p0.eps_t33 * std::exp(x[3]);
    return p;
  }
  double loss(const Eigen::VectorXd& x) const { return beta0 * std::exp(x[4]); }
  double beta(const Eigen::VectorXd& x) const {
    return damping == OeDamping::rayleigh ? loss(x) : 0.0;
  }
  double eta(const Eigen::VectorXd& x) const {
    return damping == OeDamping::complex_constants ? loss(x) : 0.0;
  }
};

// The filtered, decimated output error of one parameter vector.
class Problem {
 public:
  // With `share` (predictions on one held-out record), the record's
  // filtered spectra are taken from it when another problem made them from
  // the same samples with the same shape, and left there otherwise.
  Problem(model::ModalSolver& solver, const MaterialClass& cls, const Coordinates5& co,
          const Averaged& rec, const OeData& data, double band_hz,
          const model::ModalOptions& modal, const std::shared_ptr<OeRecordShare>& share = nullptr);

  std::size_t samples() const { return idx_.size(); }
  int evaluations() const { return evaluations_; }  // FE port models built
  double sample_rate_hz() const { return fs_; }
  // A column of this record's filtered samples that does not depend on θ,
  // under the caller's key (baseline.cpp's baseline columns: a slow basis
  // function's L ∗ b): `make` runs once per key, under a lock this problem's
  // forks share (so the work is done and counted once, whichever thread asks
  // first), and later calls return the kept column.
  using ColumnKey = OeRecordShare::ColumnKey;
  Eigen::VectorXd kept_column(const ColumnKey& key, const std::function<Eigen::VectorXd()>& make);
  // Keep them in `share` instead, if it is empty or holds this problem's shape
  // (else this problem keeps its own).
  void share_columns(const std::shared_ptr<OeRecordShare>& share);
  double transfer_bin_hz() const { return fs_ / double(nfft_); }  // spacing of T(f_k)'s bins

  // The FE port model of the material part of x (θ without β) with an end
  // mass, from a small cache: the Jacobian's β and effect columns, the
  // type-B perturbations of the chain and the re-evaluations at an answer
  // need no new modal solve. nullptr when the model cannot be built.
  const model::ModalPortModel* port_of(const Eigen::VectorXd& x, double end_mass);

  // The port models of several points at once (an exact Jacobian's columns,
  // a grid of starts), those not cached built on `threads` threads: this
  // solver and a second one on the same tube. A port model is a function of
  // its key alone (each solve starts from Spectra's fixed initial vector), so
  // the answers do not depend on the thread count.
  void prefetch(const std::vector<std::pair<Eigen::VectorXd, double>>& points);

  // The effect scan's surrogate (issue 43 item 2): with set_surrogate(true),
  // once kSurrogateAfter modal solves have been paid (armed()), a port model
  // not cached comes from a reduced basis (model/reduced_port.hpp) — the
  // exact solutions at a centre and at its plus-points (centre + h·e_c in the
  // constants and the end mass), a small dense eigenproblem per model in
  // place of a modal solve — where one reaches it (kReducedReach in every
  // constant's coordinate, kReducedMassReach in the end mass; the nearest),
  // without its error estimates (a quarter of a modal solve each; the
  // answers are made exact below); else from a modal solve. The bases: one
  // about `centre` (the optimum), built on first use,
  // once for this problem and its forks, its content — and so every answer
  // and count — the same whatever thread builds it; and one about each
  // point where an exact Jacobian is asked for (prefetch: its plus-points
  // cost what the columns would, and a run crawling along a valley takes
  // its next iterates and their Jacobians from it), this problem's own
  // until the next restore() (each task of the scan starts from the
  // optimum's state). With set_surrogate(false) the surrogate's cached
  // models are not used: a run that ended on the surrogate is evaluated
  // again on exact models and given one Gauss–Newton step on the exact
  // Jacobian (effect_scan.cpp), so that its answer is the exact model's.
  void use_reduced(const Eigen::VectorXd& centre, double end_mass);
  void set_surrogate(bool on);
  bool surrogate() const { return surrogate_; }
  void drop_reduced() {
    reduced_.reset();
    local_.clear();
    surrogate_ = false;
  }
  void set_threads(int n) { threads_ = std::max(1, n); }
  int threads() const { return threads_; }
  // A two-thread step's choice: threads() > 1, or a core lent now (spare_core.hpp).
  bool two_threads() const { return threads_ > 1 || may_borrow_core(); }

  // The same problem for another thread (the effect scan): its own FFT plan
  // and buffers, `solver` for its FE models, this one's cache and tangent.
  // Construct and destroy it on the thread that owns this one (FFTW's planner
  // is not thread-safe; executing distinct plans is).
  Problem(const Problem& o, model::ModalSolver& solver);
  Problem(const Problem&) = delete;
  Problem& operator=(const Problem&) = delete;
  // A second solver on the same tube (built on first use): prefetch's second
  // thread, or a forked Problem's.
  model::ModalSolver& second_solver();

  // The bench's known effects (OeData: a measured fixture's lead R, Cp, DAQ
  // input R and skew), as the catalogue's EffectSet (model/effects.hpp).
  const model::EffectSet& effects() const { return fx_; }
  // … with the free effect (scan_effects) at x's sixth coordinate.
  model::EffectSet effects_at(const Eigen::VectorXd& x) const {
    model::EffectSet fx = fx_;
    if (x.size() > kParams && free_) free_(fx, x[kParams]);
    return fx;
  }

  // T(f_k) = v2/v1 as recorded, for parameters x, with the bench's effects
  // (model/bench_response.hpp: the same forward model as the gap diagnosis
  // and the simulated bench's frequency-domain twin); empty when the model
  // cannot be built.
  std::optional<std::vector<cd>> transfer(const Eigen::VectorXd& x) { return transfer(x, effects_at(x)); }
  // A catalogue effect as a sixth coordinate of x (scan_effects below).
  void free_effect(std::function<void(model::EffectSet&, double)> apply) { free_ = std::move(apply); }
  std::optional<std::vector<cd>> transfer(const Eigen::VectorXd& x, const model::EffectSet& fx);

  // The port models' tangent ∂port/∂x_c (c < 4: the constants) by forward
  // differences at x_ref, from the models an exact Jacobian built there. Near
  // x_ref (|Δx| ≤ kTangentReach in every constant's coordinate, the same end
  // mass) a material column of the Jacobian is then the residual at x with
  // the port model port(x) + h·∂port/∂x_c — the frequency response still
  // computed exactly at x, only the modal quantities' slopes taken from
  // x_ref, a few per mille off: no FE model per column. The residuals, the
  // costs and the answers stay exact; an optimiser's fixed point moves by that
  // error times the residual's projection, a tiny fraction of a sigma.
  void set_tangent(const Eigen::VectorXd& x, double h) { set_tangent(x, h, effects_at(x).mass_loading); }
  void set_tangent(const Eigen::VectorXd& x, double h, double mass);
  bool tangent_near(const Eigen::VectorXd& x) { return tangent_near(x, effects_at(x).mass_loading); }
  // The tangent as a fit leaves it (null when there is none), and a fit's
  // tangent taken into this problem's coordinates (about other constants: the
  // same models, x_ref moved and the nu12 column — a relative coordinate,
  // ν/ν0 − 1 — rescaled by the ratio of the origins' ν). The adopted one
  // serves tangent_near and tangent_transfer as this problem's own would.
  std::shared_ptr<const OePortTangent> export_tangent() const;
  void adopt_tangent(const OePortTangent& t);
  // … and it still holds there: x's own port model is its linear prediction
  // from x_ref to within kTangentTolerance in every electrically active mode's
  // frequency and participation. Two modes near a veering (an avoided
  // crossing, where a few per mille of a constant swaps their shapes and
  // participations) fail it: their columns are computed exactly.
  bool tangent_near(const Eigen::VectorXd& x, double mass);
  // T at x on the tangent anchored at a point whose model is cached:
  // port(anchor) + Σ_c (x_c − anchor_c)·∂port/∂x_c — no FE model; exact at
  // the anchor, its slopes x_ref's (a trial step's screening). Empty when
  // the anchor is not near x_ref or x not near the anchor.
  std::optional<std::vector<cd>> tangent_model(const Eigen::VectorXd& anchor,
                                               const Eigen::VectorXd& x);
  // T at x with the constant c moved by h, through the tangent (tangent_near).
  std::optional<std::vector<cd>> tangent_transfer(const Eigen::VectorXd& x, int c, double h) {
    return tangent_transfer(x, c, h, effects_at(x));
  }
  std::optional<std::vector<cd>> tangent_transfer(const Eigen::VectorXd& x, int c, double h,
                                                  const model::EffectSet& fx);

  // Filtered output error for a given transfer.
  Eigen::VectorXd residual_of(const std::vector<cd>& t);

  // Filtered output error (volts) at the decimated samples.
  std::optional<Eigen::VectorXd> residual(const Eigen::VectorXd& x);

  // L ∗ (T ∗ d1 − d2) at the decimated samples (a shot's deviation from the mean).
  Eigen::VectorXd deviation(const std::vector<cd>& t, const std::vector<double>& d1,
                            const std::vector<double>& d2);

  // Expected |DFT|² shape of the decimated residual (bins j = 0..M/2 of its
  // M-point DFT) for white noise σ1 on v1 and σ2 on v2: |L|²(σ1²|T|² + σ2²),
  // folded over the aliases of the decimation.
  Eigen::VectorXd residual_psd(const std::vector<cd>& t, double s1, double s2) const;
  double residual_bin_hz() const { return fs_ / double(decim_) / double(idx_.size()); }

  // The residual in frequency at x (update/residual_regions.hpp): every r-th
  // bin of the padded transform (r = nfft/n: bins about 1/T_record apart,
  // nearly independent) in the low-pass's passband, above the lowest two
  // (the offsets), with its variance n·|L|²(σ1²|T|² + σ2²) under white noise
  // σ1 on v1 and σ2 on v2, the model's admittance and ∂T/∂Y.
  std::optional<ResidualSpectrum> residual_spectrum(const Eigen::VectorXd& x, double s1, double s2) {
    return residual_spectrum(x, effects_at(x), s1, s2);
  }
  std::optional<ResidualSpectrum> residual_spectrum(const Eigen::VectorXd& x, const model::EffectSet& fx, double s1,
                                                    double s2);

  // σ of the filtered error for white noise σ1 on v1 and σ2 on v2 (Parseval).
  double propagated_sigma(const std::vector<cd>& t, double s1, double s2) const;

 private:
  // The same modes in the same order (a mode crossing the truncation or the
  // residual pseudo-mode appearing changes the list: no tangent across it).
  static bool same_structure(const model::ModalPortModel& a, const model::ModalPortModel& b);
  // p += k·(plus − base), the tangent's difference (same_structure).
  void shift(model::ModalPortModel& p, const model::ModalPortModel& plus, double k) const;
  std::vector<cd> transfer_of(const model::ModalPortModel& port, double beta, double eta,
                              const model::EffectSet& fx) const;

  Eigen::VectorXd invert();

  using Key = Eigen::Matrix<double, 5, 1>;  // the constants' coordinates, the end mass
  using Basis = std::shared_ptr<const model::ReducedPort>;
  struct Cached {
    Key key;
    std::optional<model::ModalPortModel> port;
    unsigned long used = 0;
    Basis basis;  // the reduced basis it came from (null: a modal solve)
  };
  struct Built {
    std::optional<model::ModalPortModel> port;
    Basis basis;
  };
  static Key key_of(const Eigen::VectorXd& x, double end_mass) {
    Key key;
    key << x.head<4>(), end_mass;
    return key;
  }
  Cached* cached(const Key& key);
  // One FE port model (counted; thread-safe for distinct solvers).
  // (armed: the surrogate may answer, decided by the caller: armed().)
  Built build(model::ModalSolver& solver, const Key& key, bool armed);
  bool armed() const { return surrogate_ && reduced_ && exact_since_ >= kSurrogateAfter; }
  const model::ModalPortModel* insert(const Key& key, Built built);

  model::ModalSolver& solver_;
  std::unique_ptr<model::ModalSolver> solver2_;  // prefetch's second thread (built on first use)
  int threads_ = 1;
  const MaterialClass& cls_;
  Coordinates5 co_;
  model::ModalOptions modal_;
  double r1_;
  model::EffectSet fx_;
  std::function<void(model::EffectSet&, double)> free_;
  double fs_, band_hz_;
  std::size_t n_, nfft_;
  dsp::RealFft fft_;
  std::size_t kmax_ = 0, decim_ = 1;
  std::vector<cd> l_, lv1_, ly_, spec_;
  std::vector<double> buf_;  // invert's decimated samples
  std::vector<std::size_t> idx_;
  std::optional<dsp::DecimatedInverse> dinv_;  // the inverse DFT at idx_ only (invert)
  std::shared_ptr<OeRecordShare> columns_ = std::make_shared<OeRecordShare>();  // kept_column's (shared with the forks)
  struct Reduced {
    Key centre;  // the constants' coordinates and the end mass
    std::mutex mutex;
    bool tried = false;
    Basis basis;  // immutable once built (tried); null if it could not be
    std::shared_ptr<const model::ReducedPortSpace> space;  // every basis's (made with the first)
  };
  // The reduced bases' shared pieces (made on first use, under the lock).
  std::shared_ptr<const model::ReducedPortSpace> reduced_space();
  std::shared_ptr<Reduced> reduced_;  // use_reduced's (shared with the forks)
  std::vector<std::pair<Key, Basis>> local_;  // the Jacobians' bases (centre, basis), this problem's
  bool surrogate_ = false;
  // Modal solves since use_reduced() or restore(): the surrogate starts after
  // kSurrogateAfter of them — a short run (most of a capture without lack of
  // fit) never pays for a basis, and ends as it would without it.
  std::atomic<int> exact_since_{0};
  static constexpr int kSurrogateAfter = 6;
  // The basis a key within kSameSource of a cached model must take: that
  // model's (null: a modal solve), or nullopt when there is no such model.
  // (Read only: prefetch's threads call it at once.) A difference quotient
  // over 1e-6 of one model exact and the other reduced would be the reduced
  // model's error over 1e-6: a forward difference's point, a tangent's
  // plus-point, takes the source of the model it differs from.
  std::optional<Basis> same_source(const Key& key) const;
  // A basis of the exact solutions at `centre` and its plus-points (with
  // `mass`, one in the end mass too), on
  // `solver`, or on this problem's two solvers with two_threads; null when
  // it cannot be built.
  Basis make_basis(const Key& centre, bool mass, bool two_threads, model::ModalSolver& solver);
  // The surrogate's model at key (above).
  Built reduced_model(model::ModalSolver& solver, const Key& key);
  Built reduced_model_at(model::ModalSolver& solver, const Key& key, const model::PiezoMaterialE& m);
  std::vector<model::ReducedPort::Point> basis_points(const Key& centre, bool mass) const;  // (throws outside the domain)
  model::PiezoMaterialE material_at(const Key& key) const;
  static constexpr double kReducedReach = 0.05;      // the constants' coordinates
  static constexpr double kReducedMassReach = 0.02;  // the end mass (its fraction of the tube's)
  static constexpr double kReducedStep = 3e-3;  // the plus-points' (tests/model/test_reduced_port.cpp)
  static constexpr double kSameSource = 1e-5;
  std::atomic<int> evaluations_{0};
  // Every model a fit builds stays (least recently used out beyond this): with
  // 16, a diagnosis with its effect scan rebuilt 38 of its 566 models (refsim
  // 07); the models are small (a dozen modes) and a lookup is a scan of keys.
  static constexpr std::size_t kCache = 1024;
  static constexpr double kTangentReach = 0.05;
  // The check of tangent_near: relative error of the prediction (a veering
  // swaps participations by tens of percent, the curvature away from one
  // moves them by well under a percent within the reach).
  static constexpr double kTangentTolerance = 0.01;        // participation
  static constexpr double kTangentOmegaTolerance = 1e-3;   // frequency
  static constexpr double kActiveCoupling = 1e-4;          // p²/(ω²C0) of a mode it looks at
  static constexpr double kScreenChange = 0.05;            // tangent_model: Σ|Δx_c|·slope_c at most
  struct Tangent {
    bool valid = false;
    Eigen::Vector4d x_ref;
    double mass = 0, h = 0;
    model::ModalPortModel base;
    std::array<model::ModalPortModel, 4> plus;
    std::array<double, 4> slope{};  // largest relative slope of an active mode's ω or |p| per unit x_c
  } tangent_;
  std::vector<Cached> cache_;
  unsigned long clock_ = 0;
  // The forward spectrum of a record deviation() filters: zero (a baseline
  // column's v1, a single shot's deviation) is transformed once and kept —
  // once for all the problems that share the columns (this one, its forks,
  // the held-out predictions of one record), by whichever needs it first, so
  // the FFT count does not depend on the threads — any other into `scratch`.
  // (Keeping every record's spectrum by content was measured slower: the
  // held-out chirp's 1.6 MB spectra cost more in fresh pages and comparisons
  // than the transforms they saved.)
  const std::vector<cd>& spectrum_of(const std::vector<double>& record, std::vector<cd>& scratch);

 public:
  // What the optimiser leaves behind (the cached models, the tangent): each
  // scanned effect starts from the optimum's, so its answer does not depend on
  // the order of the scan or the thread it runs on.
  struct State {
    std::vector<Cached> cache;
    Tangent tangent;
    unsigned long clock = 0;
  };
  State state() const { return {cache_, tangent_, clock_}; }
  void restore(const State& s) {
    cache_ = s.cache;
    tangent_ = s.tangent;
    clock_ = s.clock;
    local_.clear();
    exact_since_ = 0;
  }
};

}  // namespace piezo::update::oe
