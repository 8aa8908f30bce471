#pragma once
// The picture a recorded run drew (its `/arbiter/scene` messages, foxglove.SceneUpdate as
// SceneUpdates writes them), as a viewer shows it step by step, drawn again by a replay's
// interface layer (RecordedInputs) with the plugin drawing API: a replay's recording and its
// Foxglove server carry the recorded picture on the channel and in the form a run does.

#include <cstdint>
#include <string>
#include <vector>

#include "arbiter/behaviour.hpp"
#include "arbiter/scene.hpp"

namespace arbiter {

class RecordedScene {
 public:
  /// Applies a step's message as a viewer does (deletions, then entities replacing those of the
  /// same id): false, with `error` saying what was expected where ("entities[0].id: expected
  /// ..."), when it is not a SceneUpdate as a recorder writes it; the picture is then left as it
  /// was. Parses and allocates: between steps.
  bool apply(const std::string& message, std::string& error);
  /// Nothing shown, as before a recording's first message.
  void clear() {
    entities_.clear();
    frames_.clear();
  }
  bool empty() const { return entities_.empty(); }

  /// Draws what a viewer shows now into the step's picture, frame by frame: its arrows, filled
  /// circles, lines and texts, each kind's still and moving primitives in the order the recorded
  /// run drew them, as far as its messages tell it (docs/replay.md), so that the replay's
  /// SceneUpdates finds what moved as the recorded run's did. Allocation-free.
  void draw(const StepContext& ctx) const;

 private:
  struct Primitive {
    SceneShape shape = SceneShape::kLine;
    bool filled = false;
    SceneColor color;
    double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;
    double size = 0.0;
    std::uint32_t begin = 0;  ///< kLine, kPolygon: its first point; kText: its text's index
    std::uint32_t count = 0;  ///< kLine, kPolygon: its points
  };
  struct Entity {
    std::string id;
    std::string frame;
    bool still = false;
    std::vector<Primitive> primitives;
    std::vector<ScenePoint> points;
    std::vector<std::string> texts;
    // Where each kind starts in `primitives`: arrows, filled circles, lines, texts, the end.
    std::uint32_t kinds[5] = {};
  };

  struct Frame {
    std::string name;
    std::size_t begin = 0, end = 0;  // its entities
    // The order its primitives are drawn in, each slot the next one of a kind (the slot / 2),
    // still (odd) or moving; those beyond come after, the still ones first, kind by kind.
    std::vector<std::uint8_t> order;
  };
  // Visits the primitives of `frame` of `entities`, in the order drawn.
  template <typename Visit>
  static void each(const Frame& frame, const std::vector<Entity>& entities, Visit visit);

  std::vector<Entity> entities_;  // each frame's still one, then its moving one
  std::vector<Frame> frames_;
};

}  // namespace arbiter
