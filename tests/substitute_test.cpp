// Substitution: a config's model with some classes replaced runs the replacements in place of the
// originals, and a target that names nothing, or several things, is a located error.

#include <catch2/catch.hpp>

#include "arbiter/manager.hpp"
#include "arbiter/program.hpp"
#include "arbiter/substitute.hpp"
#include "test_support.hpp"

using namespace arbiter;

namespace {

const char* const kConfig = R"(arbiter: 1
name: subject
layers:
  - name: world
    interface: test.Feed
    actuators:
      out: {type: double}
  - name: control
    sensors: [out]
    actuators:
      kick: {type: bool}
    behaviours:
      kick_ball: {type: scripted, params: {activation: 0, writes: {kick: true}}}
      walk: {type: scripted, params: {activation: 1}}
    inhibitions:
      - kick_ball => walk
  - name: head
    actuators:
      angle: {type: double}
    behaviours:
      walk: test.NanLevel
state_machines:
  plan:
    states:
      wait: {type: scripted, params: {hold: 5}}
      go: {type: scripted, params: {hold: 1}}
    queue: [wait, go]
)";

struct Subject {
  Registry registry = test::make_test_registry();
  Diagnostics diagnostics;
  Model model;

  Subject() {
    auto root = parse_document(kConfig, "subject.yaml", DocumentFormat::kYaml, diagnostics);
    REQUIRE(root);
    model = build_model(*root, registry, diagnostics);
    INFO(format(diagnostics));
    REQUIRE_FALSE(diagnostics.has_errors());
  }

  /// Substitutes `target` by the replacement written as YAML (at line 1 of "test.yaml").
  bool substitute(const std::string& target, const std::string& replacement) {
    auto node = parse_document(replacement, "test.yaml", DocumentFormat::kYaml, diagnostics);
    REQUIRE(node);
    // Field by field: braced, GCC 12 at -O2 warns, falsely, that its location may be used
    // uninitialised.
    Substitution substitution;
    substitution.target = target;
    substitution.location.file = "test.yaml";
    substitution.location.line = 7;
    substitution.location.column = 3;
    substitution.declaration = *node;
    return arbiter::substitute(model, {substitution}, registry, diagnostics);
  }

  Manager run(int steps) {
    auto program = compile(model, registry, diagnostics);
    INFO(format(diagnostics));
    REQUIRE(program);
    Manager manager(std::move(*program));
    for (int i = 0; i < steps; ++i) manager.step();
    return manager;
  }
};

}  // namespace

TEST_CASE("a substituted behaviour runs in place of the original, under the config's inhibitions",
          "[substitute]") {
  Subject subject;
  REQUIRE(subject.substitute("control/kick_ball",
                             "{type: scripted, params: {activation: 1, writes: {kick: true}}}"));
  Manager manager = subject.run(1);
  const Program& program = manager.program();
  CHECK(manager.active(*program.find_behaviour("control", "kick_ball")));
  CHECK_FALSE(manager.active(*program.find_behaviour("control", "walk")));
  CHECK(manager.actuator<bool>(*program.find_actuator("kick")));
}

TEST_CASE("a whole class is substituted wherever the config uses it", "[substitute]") {
  Subject subject;
  REQUIRE(subject.substitute("test.NanLevel", "{type: scripted, params: {activation: 1}}"));
  Manager manager = subject.run(1);
  CHECK(manager.active(*manager.program().find_behaviour("head", "walk")));
}

TEST_CASE("a class name shared by a behaviour and a state class is ambiguous", "[substitute]") {
  Subject subject;
  CHECK_FALSE(subject.substitute("scripted", "scripted"));
  CHECK(format(subject.diagnostics).find("'scripted' is ambiguous") != std::string::npos);
}

TEST_CASE("a substituted state keeps its place in the plan", "[substitute]") {
  Subject subject;
  REQUIRE(subject.substitute("plan/wait", "{type: scripted, params: {hold: 1}}"));
  Manager manager = subject.run(2);
  CHECK(manager.program().find_controller("plan")->current_state() == "go");
}

TEST_CASE("an interface layer is substituted by an interface class", "[substitute]") {
  Subject subject;
  REQUIRE(subject.substitute("world", "test.Feed"));
  Subject wrong_kind;
  CHECK_FALSE(wrong_kind.substitute("world", "scripted"));
  CHECK(format(wrong_kind.diagnostics)
            .find("test.yaml:1:1: error: 'scripted' is a behaviour class") != std::string::npos);
}

TEST_CASE("an unknown or ambiguous target is a located error that says what to write",
          "[substitute]") {
  Subject unknown;
  CHECK_FALSE(unknown.substitute("kick_bal", "scripted"));
  CHECK(format(unknown.diagnostics)
            .find("test.yaml:7:3: error: 'kick_bal' names no behaviour, state, interface layer or "
                  "class of config 'subject'\ntest.yaml:7:3: note: did you mean 'kick_ball'?") ==
        0);

  Subject ambiguous;
  CHECK_FALSE(ambiguous.substitute("walk", "scripted"));
  CHECK(format(ambiguous.diagnostics) ==
        "test.yaml:7:3: error: 'walk' is ambiguous: it names behaviour 'control/walk', behaviour "
        "'head/walk'\n"
        "test.yaml:7:3: note: write one of: control/walk, head/walk\n");

  Subject layer;
  CHECK_FALSE(layer.substitute("head", "scripted"));
  CHECK(format(layer.diagnostics).find("layer 'head' is not an interface layer") !=
        std::string::npos);
}

TEST_CASE("a replacement's params are checked against its class", "[substitute]") {
  Subject subject;
  CHECK_FALSE(subject.substitute("kick_ball", "{type: scripted, params: {activaton: 1}}"));
  INFO(format(subject.diagnostics));
  CHECK(format(subject.diagnostics).find("test.yaml:1:27: error: unknown param 'activaton'") !=
        std::string::npos);
}
