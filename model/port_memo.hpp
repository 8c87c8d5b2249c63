#pragma once
// Port models remembered by what they are a function of (issue 43).
//
// A port model (ModalSolver::port_model) depends on the tube, the material,
// the modal options and the solver's physical checks alone: every Lanczos
// run starts from Spectra's fixed initial vector, and a kept factorisation
// is bit for bit a fresh one (CoupledFactor; test_model_skyline_ldlt). So a
// model asked for again — by another stage of a capture's pipeline (the
// held-out predictions at the fit's answers, the per-mode figures at its
// constants, the effects' regrid at the coarse grid's points) or by another
// capture of the same tube and nominal material (its nominal model and the
// coarse grid) — is the same bits as the one solved before, and is taken
// from here instead of solved again. The answers therefore do not depend on
// whether a model was remembered, nor on which solver or thread asked first.
//
// One memo per tube (TubeModel), shared by the solvers on it and safe to use
// from several threads; at most `capacity` models (about a kilobyte each),
// the least recently used dropped first.
//
// The work counters (model/work_counters.hpp) stay each capture's own: a
// solver reads the memo as a `reader` (a capture: new_reader()), and a model
// that another reader put there counts as a modal solve the first time this
// reader takes it — what the capture replayed alone would have solved — so a
// capture's counts do not depend on which captures a worker replayed before
// it (test_replay: shards and one run give the same records). The solves
// saved across captures are counted in g_modal_solves_remembered.
// (The entry remembers its last reader only: exact when captures take turns,
// as a replay worker's and the GUI's do; two captures of one tube running at
// once in one process could count a shared model twice — the counts, never
// the models.)
#include <array>
#include <cstddef>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <unordered_map>
#include <utility>

#include "model/material.hpp"
#include "model/port_model.hpp"
#include "model/tube_model.hpp"

namespace piezo::model {

struct ModalOptions;

class PortModelMemo {
 public:
  // The memo of `tube`'s port models (the whole tube, as ModalSolver holds it).
  explicit PortModelMemo(std::shared_ptr<const TubeModel> tube, std::size_t capacity = 1024);
  const TubeModel* tube() const { return tube_.get(); }

  // The model remembered for these inputs, if any (and it becomes the most
  // recently used).
  std::optional<ModalPortModel> find(const PiezoMaterialE& material, const ModalOptions& options,
                                     bool physical_checks, long reader = 0);
  // Remembers `port` for these inputs (the least recently used model goes
  // when the memo is full).
  void insert(const PiezoMaterialE& material, const ModalOptions& options, bool physical_checks,
              const ModalPortModel& port, long reader = 0);
  // A reader id not given before (process-wide).
  static long new_reader();

  std::size_t size() const;
  std::size_t capacity() const { return capacity_; }
  long hits() const;

  // Every input a port model depends on, bit for bit (−0 and +0 differ: a
  // miss, never a wrong model).
  using Key = std::array<std::uint64_t, 21>;

 private:
  struct KeyHash {
    std::size_t operator()(const Key& k) const;
  };
  static Key key_of(const PiezoMaterialE& material, const ModalOptions& options, bool physical_checks);

  std::shared_ptr<const TubeModel> tube_;  // kept alive: its address identifies the tube
  std::size_t capacity_;
  mutable std::mutex mutex_;
  struct Entry {
    Key key;
    ModalPortModel port;
    long reader;  // the last reader that solved or took it
  };
  std::list<Entry> lru_;  // most recently used first
  std::unordered_map<Key, std::list<Entry>::iterator, KeyHash> index_;
  long hits_ = 0;
};

}  // namespace piezo::model
