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

/// One primitive, as the step wrote it: one 64-byte cache line, so that an observer copies a
/// step's picture in few lines. Its frame's name and its text are copied into the step's strings
/// (SceneData::strings; read them with ScenePicture::frame() and text()): a primitive holds no
/// pointer into plugin code, which a hot reload may unload.
struct ScenePrimitive {
  static constexpr std::size_t kFrameBytes = 16;  ///< a longer frame name is cut
  static constexpr std::size_t kTextBytes = 40;   ///< a longer text is cut

  SceneShape shape = SceneShape::kLine;
  bool filled = false;
  std::uint16_t frame = 0;  ///< its frame's name: kFrameBytes in the step's strings, from here
  std::uint16_t point_begin = 0;  ///< kLine, kPolygon: the first of the step's points; kText: the
                                  ///< first byte of its text in the step's strings
  std::uint16_t point_count = 0;  ///< kLine, kPolygon: how many points; kText: the text's bytes
  SceneColor color;
  double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;  ///< kCircle: x1 is its outline's width
  double size = 0.0;  ///< a line's width, a circle's radius, a text's height (m)
};
static_assert(sizeof(ScenePrimitive) == 64, "a primitive is one cache line");

/// A step's picture as an observer reads it: the primitives, the points of their lines, the
/// strings their frames and texts are in, and how many primitives were dropped.
struct ScenePicture {
  const ScenePrimitive* primitives = nullptr;
  std::size_t count = 0;
  const ScenePoint* points = nullptr;
  const char* strings = nullptr;
  std::size_t dropped = 0;

  /// The name of `p`'s frame, as copied (cut to kFrameBytes - 1 bytes).
  const char* frame(const ScenePrimitive& p) const { return strings + p.frame; }
  /// The bytes of a kText's text, as copied (cut to kTextBytes - 1 bytes): not NUL-terminated.
  const char* text(const ScenePrimitive& p) const { return strings + p.point_begin; }
  std::size_t text_size(const ScenePrimitive& p) const { return p.point_count; }
  /// The points and strings the primitives use: a copy of the picture needs no more of them.
  std::size_t point_end() const {
    std::size_t end = 0;
    for (std::size_t i = 0; i < count; ++i) {
      const auto& p = primitives[i];
      if (p.shape == SceneShape::kLine || p.shape == SceneShape::kPolygon) {
        end = end > p.point_begin + p.point_count ? end : p.point_begin + p.point_count;
      }
    }
    return end;
  }
  std::size_t string_end() const {
    std::size_t end = 0;
    for (std::size_t i = 0; i < count; ++i) {
      const auto& p = primitives[i];
      const std::size_t frame_end = p.frame + ScenePrimitive::kFrameBytes;
      end = end > frame_end ? end : frame_end;
      if (p.shape == SceneShape::kText) {
        end = end > p.point_begin + p.point_count ? end : p.point_begin + p.point_count;
      }
    }
    return end;
  }
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
  /// The frames' names (kFrameBytes each, the rest zeroed) and the texts, in the order drawn.
  char* strings = nullptr;
  std::size_t string_capacity = 0;
  std::size_t string_size = 0;
  /// Where each frame drawn in this step has its name in the strings, in the order first drawn.
  std::uint16_t* frames = nullptr;
  std::size_t frame_capacity = 0;
  std::size_t frame_count = 0;
  /// Primitives dropped this step: beyond the capacity, or their points (or text, or frame)
  /// beyond the room for them.
  std::size_t dropped = 0;
  /// Drawing is ignored, and not counted as dropped: the rest of a step whose picture is a
  /// recorded one (Manager::keep_input_pass_scene_only).
  bool muted = false;

  /// What was drawn, as an observer reads it.
  ScenePicture picture() const {
    return {primitives, primitive_count < primitive_capacity ? primitive_count : primitive_capacity,
            points, strings, dropped};
  }
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
    std::size_t size = 0;
    while (text != nullptr && text[size] != '\0' && size + 1 < ScenePrimitive::kTextBytes) ++size;
    ScenePrimitive* p = add(SceneShape::kText, color);
    if (p == nullptr) return;
    if (data_->string_size + size > data_->string_capacity ||
        data_->string_size + size > UINT16_MAX) {
      --data_->primitive_count;
      ++data_->dropped;
      return;
    }
    p->x0 = at.x;
    p->y0 = at.y;
    p->size = height;
    p->point_begin = static_cast<std::uint16_t>(data_->string_size);
    p->point_count = static_cast<std::uint16_t>(size);
    for (std::size_t i = 0; i < size; ++i) data_->strings[data_->string_size++] = text[i];
  }

 private:
  static constexpr std::uint32_t kUnresolved = ~std::uint32_t{0};

  // The step's place of this frame's name in the strings, added when first drawn in: false when
  // there is no room for it. The name is read at every primitive, as it was copied into each.
  bool resolve(std::uint16_t& at) {
    char name[ScenePrimitive::kFrameBytes] = {};
    for (std::size_t i = 0;
         frame_ != nullptr && frame_[i] != '\0' && i + 1 < ScenePrimitive::kFrameBytes; ++i) {
      name[i] = frame_[i];
    }
    const auto same = [&](std::size_t index) {
      const char* known = data_->strings + data_->frames[index];
      for (std::size_t i = 0; i < ScenePrimitive::kFrameBytes; ++i) {
        if (known[i] != name[i]) return false;
      }
      return true;
    };
    if (frame_index_ < data_->frame_count && same(frame_index_)) {
      at = data_->frames[frame_index_];
      return true;
    }
    for (std::size_t index = 0; index < data_->frame_count; ++index) {
      if (!same(index)) continue;
      frame_index_ = static_cast<std::uint32_t>(index);
      at = data_->frames[index];
      return true;
    }
    if (data_->frame_count >= data_->frame_capacity ||
        data_->string_size + ScenePrimitive::kFrameBytes > data_->string_capacity ||
        data_->string_size + ScenePrimitive::kFrameBytes > UINT16_MAX) {
      return false;
    }
    frame_index_ = static_cast<std::uint32_t>(data_->frame_count);
    at = static_cast<std::uint16_t>(data_->string_size);
    data_->frames[data_->frame_count++] = at;
    for (std::size_t i = 0; i < ScenePrimitive::kFrameBytes; ++i) {
      data_->strings[data_->string_size++] = name[i];
    }
    return true;
  }
  ScenePrimitive* add(SceneShape shape, SceneColor color) {
    if (data_->muted) return nullptr;
    std::uint16_t frame = 0;
    if (data_->primitive_count >= data_->primitive_capacity || !resolve(frame)) {
      ++data_->dropped;
      return nullptr;
    }
    ScenePrimitive& p = data_->primitives[data_->primitive_count++];
    p.shape = shape;
    p.filled = false;
    p.frame = frame;
    p.point_begin = 0;
    p.point_count = 0;
    p.color = color;
    p.x0 = p.y0 = p.x1 = p.y1 = p.size = 0.0;
    return &p;
  }
  void add_points(SceneShape shape, const ScenePoint* points, std::size_t count, SceneColor color,
                  double width) {
    if (data_->muted) return;
    const std::size_t least = shape == SceneShape::kPolygon ? 3 : 2;
    if (count < least || count > UINT16_MAX || data_->point_count + count > data_->point_capacity ||
        data_->point_count > UINT16_MAX) {
      ++data_->dropped;
      return;
    }
    ScenePrimitive* p = add(shape, color);
    if (p == nullptr) return;
    p->point_begin = static_cast<std::uint16_t>(data_->point_count);
    p->point_count = static_cast<std::uint16_t>(count);
    p->size = width;
    for (std::size_t i = 0; i < count; ++i) data_->points[data_->point_count++] = points[i];
  }

  detail::SceneData* data_;
  const char* frame_;
  std::uint32_t frame_index_ = kUnresolved;  // a guess: checked against the name at every draw
};

}  // namespace arbiter
