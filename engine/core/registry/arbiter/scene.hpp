#pragma once
// A picture of the world, drawn by plugin code in a step (StepContext::scene()): lines, polygons,
// circles, arrows and text in a named frame, written into buffers laid out when the manager is
// made, so that drawing never allocates. Observers copy the step's primitives with its values: a
// recording carries them on /arbiter/scene (foxglove.SceneUpdate), the live page draws them beside
// the graph. docs/plugins.md, "Drawing the world".

#include <cstddef>
#include <cstdint>

namespace arbiter {

/// An RGBA colour, each channel in [0, 1].
struct SceneColor {
  float r = 0.0f, g = 0.0f, b = 0.0f, a = 1.0f;
};

/// A point of the frame drawn in, in metres.
struct ScenePoint {
  double x = 0.0, y = 0.0;
};

/// What a primitive is. The numbers are part of the plugin API.
enum class SceneShape : std::uint8_t {
  kLine = 0,     ///< a polyline through its points (a line: two points)
  kPolygon = 1,  ///< a closed polyline through its points
  kCircle = 2,   ///< centre (x0, y0), radius `size`; filled or its outline
  kArrow = 3,    ///< from (x0, y0) to (x1, y1)
  kText = 4,     ///< `text` at (x0, y0), `size` high
};

/// One primitive, as the step wrote it. Frame and text are copied into it: a primitive holds no
/// pointer into plugin code, which a hot reload may unload.
struct ScenePrimitive {
  static constexpr std::size_t kFrameBytes = 16;  ///< a longer frame name is cut
  static constexpr std::size_t kTextBytes = 40;   ///< a longer text is cut

  SceneShape shape = SceneShape::kLine;
  bool filled = false;
  std::uint16_t point_count = 0;  ///< kLine, kPolygon: in the step's points
  std::uint32_t point_begin = 0;  ///< kLine, kPolygon: the first
  SceneColor color;
  double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;  ///< kCircle: x1 is its outline's width
  double size = 0.0;  ///< a line's width, a circle's radius, a text's height (m)
  char frame[kFrameBytes] = {};
  char text[kTextBytes] = {};
};

namespace detail {

/// A step's drawing: buffers sized at load, counts reset at the start of every step. Counts go
/// on past the capacity so that what was dropped can be told.
struct SceneData {
  ScenePrimitive* primitives = nullptr;
  std::size_t primitive_capacity = 0;
  std::size_t primitive_count = 0;
  ScenePoint* points = nullptr;
  std::size_t point_capacity = 0;
  std::size_t point_count = 0;
  /// Primitives dropped this step: beyond the capacity, or their points beyond the points'.
  std::size_t dropped = 0;
};

}  // namespace detail

/// Draws into the step's picture, in one frame ("field", "robot"; a viewer's fixed frame is the
/// first one drawn). Get it from StepContext::scene(); cheap to copy, valid in the step only.
/// Allocation-free: a primitive beyond the per-step capacity (Manager::kScenePrimitivesPerStep,
/// kScenePointsPerStep) is dropped and counted, never stored.
class Scene {
 public:
  Scene(detail::SceneData& data, const char* frame) : data_(&data), frame_(frame) {}

  /// A segment from `a` to `b`, `width` metres wide.
  void line(ScenePoint a, ScenePoint b, SceneColor color, double width = 0.02) {
    const ScenePoint points[] = {a, b};
    polyline(points, 2, color, width);
  }
  /// A polyline through `count` points; fewer than 2 draw nothing (counted as dropped).
  void polyline(const ScenePoint* points, std::size_t count, SceneColor color,
                double width = 0.02) {
    add_points(SceneShape::kLine, points, count, color, width);
  }
  /// A closed outline through `count` points; fewer than 3 draw nothing (counted as dropped).
  void polygon(const ScenePoint* points, std::size_t count, SceneColor color, double width = 0.02) {
    add_points(SceneShape::kPolygon, points, count, color, width);
  }
  /// A circle: its outline `width` wide, or a filled disc.
  void circle(ScenePoint centre, double radius, SceneColor color, bool filled = false,
              double width = 0.02) {
    if (ScenePrimitive* p = add(SceneShape::kCircle, color)) {
      p->x0 = centre.x;
      p->y0 = centre.y;
      p->x1 = width;
      p->size = radius;
      p->filled = filled;
    }
  }
  /// An arrow from `from` to `to` (its head at `to`), `width` metres thick.
  void arrow(ScenePoint from, ScenePoint to, SceneColor color, double width = 0.05) {
    if (ScenePrimitive* p = add(SceneShape::kArrow, color)) {
      p->x0 = from.x;
      p->y0 = from.y;
      p->x1 = to.x;
      p->y1 = to.y;
      p->size = width;
    }
  }
  /// `text` (copied, cut to ScenePrimitive::kTextBytes - 1 bytes) at `at`, `height` metres high.
  void text(ScenePoint at, const char* text, SceneColor color, double height = 0.3) {
    if (ScenePrimitive* p = add(SceneShape::kText, color)) {
      p->x0 = at.x;
      p->y0 = at.y;
      p->size = height;
      copy(text, p->text, ScenePrimitive::kTextBytes);
    }
  }

 private:
  static void copy(const char* from, char* to, std::size_t bytes) {
    std::size_t i = 0;
    for (; from != nullptr && from[i] != '\0' && i + 1 < bytes; ++i) to[i] = from[i];
    to[i] = '\0';
  }
  ScenePrimitive* add(SceneShape shape, SceneColor color) {
    if (data_->primitive_count >= data_->primitive_capacity) {
      ++data_->dropped;
      return nullptr;
    }
    ScenePrimitive& p = data_->primitives[data_->primitive_count++];
    p.shape = shape;
    p.filled = false;
    p.point_count = 0;
    p.point_begin = 0;
    p.color = color;
    p.x0 = p.y0 = p.x1 = p.y1 = p.size = 0.0;
    copy(frame_, p.frame, ScenePrimitive::kFrameBytes);
    p.text[0] = '\0';
    return &p;
  }
  void add_points(SceneShape shape, const ScenePoint* points, std::size_t count, SceneColor color,
                  double width) {
    const std::size_t least = shape == SceneShape::kPolygon ? 3 : 2;
    if (count < least || count > UINT16_MAX || data_->point_count + count > data_->point_capacity) {
      ++data_->dropped;
      return;
    }
    ScenePrimitive* p = add(shape, color);
    if (p == nullptr) return;
    p->point_begin = static_cast<std::uint32_t>(data_->point_count);
    p->point_count = static_cast<std::uint16_t>(count);
    p->size = width;
    for (std::size_t i = 0; i < count; ++i) data_->points[data_->point_count++] = points[i];
  }

  detail::SceneData* data_;
  const char* frame_;
};

}  // namespace arbiter
