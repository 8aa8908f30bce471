#pragma once
// engine/core/compile: a Model in; a Program out: classes instantiated, SCL controllers built,
// layers topologically sorted, names resolved to indices (load.hpp: file to Program in one call).
//
// Stage 3 of the data path: the compiled program. Names are resolved to indices, the chaining
// closure and topological order are computed, classes are instantiated and their ports bound,
// and every buffer the step needs is sized. The Program is the fixed structure; the Manager
// holds what changes from step to step.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "arbiter/behaviour.hpp"
#include "arbiter/controller.hpp"
#include "arbiter/diagnostics.hpp"
#include "arbiter/model.hpp"
#include "arbiter/registry.hpp"

namespace arbiter {

struct CompiledBehaviour {
  std::string name;
  const ClassInfo* cls = nullptr;
  SourceLocation location;
  std::uint32_t layer = 0;
  std::unique_ptr<Behaviour> instance;
  FaultPolicy on_exception = FaultPolicy::kInactive;  ///< its own, or the config's
};

struct CompiledInhibition {
  std::uint32_t inhibitor = 0;  ///< behaviour indices (execution order)
  std::uint32_t inhibited = 0;
  bool chaining = false;
  bool implicit = false;    ///< implied by a chain of chaining inhibitions, not declared
  SourceLocation location;  ///< where declared; for an implicit one, its inhibited behaviour
};

/// The inhibitions of a compiled program (docs/semantics.md, "Inhibitions and their closure"). What
/// is kept is the declared ones, compactly, and a short recipe per behaviour from which the step
/// refines levels over the chaining closure (docs/semantics.md, "Refinement") without walking it:
/// the closure of a chain of N behaviours has N(N-1)/2 edges. As a list it holds the declared and
/// the implicit inhibitions, by layer, then inhibited, then inhibitor (execution order); the list
/// is built on first use (thread-safe) and kept, for tools: the step, the trace and closed() never
/// build it.
class Inhibitions {
 public:
  /// A declared inhibition, compactly: its location is `files()[file]:line:column`.
  struct Declared {
    std::uint32_t inhibitor = 0;  ///< behaviour indices (execution order)
    std::uint32_t inhibited = 0;
    std::uint32_t file = 0;
    int line = 0;
    int column = 0;
    bool chaining = false;
  };

  /// How the step refines each behaviour b (see recipes()).
  struct Recipes {
    std::vector<std::uint32_t> begin;  ///< behaviours + 1: b's terms are [begin[b], begin[b+1])
    std::vector<std::uint32_t> split;  ///< behaviours: [begin[b], split[b]) is the chained part
    std::vector<std::uint32_t> terms;
  };

  using const_iterator = std::vector<CompiledInhibition>::const_iterator;

  Inhibitions() = default;
  /// Built by compile(): `declared` sorted by inhibited, then inhibitor; `behaviours` is
  /// Program::behaviours, whose buffer (which moving a Program keeps) gives implicit locations.
  Inhibitions(std::vector<std::string> files, std::vector<Declared> declared, Recipes recipes,
              const std::vector<CompiledBehaviour>& behaviours);

  /// Declared and implicit inhibitions; counted without building the list.
  std::size_t size() const { return closed_begin_.empty() ? 0 : closed_begin_.back(); }
  bool empty() const { return size() == 0; }
  /// The list: built on first use, O(closure) time and memory.
  const_iterator begin() const { return list().begin(); }
  const_iterator end() const { return list().end(); }
  const CompiledInhibition& operator[](std::size_t index) const { return list()[index]; }

  /// Every inhibitor of `behaviour` after closure (declared, or implied by chaining), in
  /// execution order, into `out` (replacing its contents); allocates only for `out` to grow.
  /// O(those inhibitors · log), whatever the size of the graph.
  void closed(std::uint32_t behaviour, std::vector<std::uint32_t>& out) const;
  std::vector<std::uint32_t> closed(std::uint32_t behaviour) const;
  /// How many inhibitors `behaviour` has after closure.
  std::size_t closed_count(std::uint32_t behaviour) const {
    return closed_begin_[behaviour + 1] - closed_begin_[behaviour];
  }
  /// The same inhibitors with how each comes about (declared or implicit, and where), as the
  /// list has them, without building the list.
  std::vector<CompiledInhibition> of(std::uint32_t behaviour) const;

  /// The declared inhibition of `inhibited` by `inhibitor`, or nullptr.
  const CompiledInhibition* declared(std::uint32_t inhibitor, std::uint32_t inhibited) const;
  /// The declared inhibitions, compactly, by inhibited, then inhibitor.
  const std::vector<Declared>& declared_inhibitions() const { return declared_; }
  const std::vector<std::string>& files() const { return files_; }
  /// The shortest chain of declared chaining inhibitions `from => ... => to`, as behaviour
  /// indices; empty when there is none.
  std::vector<std::uint32_t> chain(std::uint32_t from, std::uint32_t to) const;

  /// The refinement recipes. The step keeps two factors per behaviour i: factor[2i] = 1 - a[i],
  /// and factor[2i+1] = (1 - a[i]) * Q[i], where Q[i] is the product of (1 - a) over every
  /// behaviour chained to i (a chain of chaining inhibitions leads from it to i). A term t names
  /// factor[t]. The chained part of b's terms multiplies to Q[b]: it covers b's chained
  /// inhibitors as a disjoint union of blocks (odd terms: a behaviour with everything chained to
  /// it) and single behaviours (even terms). The other terms are b's non-chaining inhibitors
  /// outside that union. So a[b] = r[b] * Q[b] * the other terms is the product over b's
  /// closed inhibitors, computed in time proportional to the terms: a chain has one per
  /// behaviour.
  const Recipes& recipes() const { return recipes_; }

 private:
  struct Lists;
  const std::vector<CompiledInhibition>& list() const;
  CompiledInhibition make(std::uint32_t inhibitor, std::uint32_t inhibited) const;
  const Declared* find_declared(std::uint32_t inhibitor, std::uint32_t inhibited) const;

  std::vector<std::string> files_;
  std::vector<Declared> declared_;
  std::vector<std::uint32_t> declared_begin_;  // behaviours + 1, by inhibited
  std::vector<std::uint32_t> chaining_out_;    // declared_ indices, by inhibitor then inhibited
  std::vector<std::uint32_t> chaining_out_begin_;
  Recipes recipes_;
  std::vector<std::size_t> closed_begin_;  // behaviours + 1: list index of b's first inhibition
  const CompiledBehaviour* behaviours_ = nullptr;
  std::shared_ptr<Lists> lists_;  // built on demand; shared_ptr: Lists is incomplete here
};

struct CompiledActuator {
  std::string name;
  const ValueType* type = nullptr;
  bool aggregate = false;
  std::uint32_t layer = 0;
  std::uint32_t offset = 0;  ///< into the value buffer
  std::optional<Node> default_value;
  /// What the actuator carries in the safe-value pass of a pausing or stopping engine.
  std::optional<Node> safe_value;
  SourceLocation location;
};

/// One writer's contribution to an actuator: a behaviour's (or an interface's) output.
struct WriterSlot {
  std::uint32_t actuator = 0;
  std::uint32_t owner = 0;  ///< a behaviour index, or kNoBehaviour for the layer's interface
  std::uint32_t offset = 0;
};

struct CompiledLayer {
  std::string name;
  SourceLocation location;
  bool normalise = false;
  const ClassInfo* interface_class = nullptr;
  std::unique_ptr<Interface> interface;
  std::uint32_t behaviour_begin = 0;  ///< behaviours [begin, end) in execution order
  std::uint32_t behaviour_end = 0;
  std::uint32_t actuator_begin = 0;  ///< actuators [begin, end) declared by this layer
  std::uint32_t actuator_end = 0;
  std::vector<std::uint32_t> sensors;  ///< actuator indices, as declared
  bool is_interface() const { return interface_class != nullptr; }
};

class Program {
 public:
  Program() = default;
  Program(Program&&) noexcept = default;
  Program& operator=(Program&&) noexcept = default;

  /// Plugin libraries the classes come from. First member: destroyed after every instance.
  std::vector<std::shared_ptr<void>> libraries;

  std::string name;
  double rate_hz = 15.0;
  /// The config's `steps:`, how many steps `arbiter run` takes without `--steps`; 0: not set.
  std::uint64_t steps = 0;
  FaultPolicy on_exception = FaultPolicy::kInactive;  ///< the config's; interfaces follow it
  std::vector<CompiledLayer> layers;
  std::vector<CompiledBehaviour> behaviours;  ///< layer by layer, each in topological order
  /// Declared and implicit inhibitions, by layer, then inhibited, then inhibitor; each
  /// behaviour's inhibitors after closure (inhibitions.closed()); the step's recipes.
  Inhibitions inhibitions;
  std::vector<CompiledActuator> actuators;  ///< layer by layer, as declared
  std::vector<WriterSlot> slots;
  /// Writer slots per actuator, CSR, each list in the writers' execution order.
  std::vector<std::uint32_t> actuator_slot_begin;
  std::vector<std::uint32_t> actuator_slots;
  std::size_t value_bytes = 0;  ///< size of the value buffer
  std::size_t max_writers = 0;  ///< the most writers any actuator has
  std::vector<const ValueType*> slot_types;
  std::vector<std::uint32_t> slot_offsets;
  std::vector<std::uint32_t> actuator_offsets;
  /// SCL controllers in declaration order; owned ones are stepped by their owner only.
  std::vector<std::unique_ptr<Controller>> controllers;
  /// The model it was compiled from, when load_config() compiled it (else null): a hot reload
  /// compares params with it. Read-only from here on.
  std::shared_ptr<const Model> model;

  /// Index of a behaviour by layer and name, for tests and tools (not for the step).
  std::optional<std::uint32_t> find_behaviour(std::string_view layer, std::string_view name) const;
  std::optional<std::uint32_t> find_actuator(std::string_view name) const;
  Controller* find_controller(std::string_view name) const;

  /// The chain of chaining inhibitions `from => ... => to` behind an implicit inhibition,
  /// as behaviour indices; empty when there is none.
  std::vector<std::uint32_t> chain(std::uint32_t from, std::uint32_t to) const {
    return inhibitions.chain(from, to);
  }

  /// The declared inhibition of `inhibited` by `inhibitor`, or nullptr.
  const CompiledInhibition* declared(std::uint32_t inhibitor, std::uint32_t inhibited) const {
    return inhibitions.declared(inhibitor, inhibited);
  }
};

/// Compiles a model whose validation reported no error. Cycles and failures of classes' init()
/// are reported; returns nullopt when anything was an error. The registry (and any plugin its
/// classes came from) must outlive the program.
std::optional<Program> compile(const Model& model, const Registry& registry,
                               Diagnostics& diagnostics);

}  // namespace arbiter
