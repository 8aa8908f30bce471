#include "arbiter/recorded_scene.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "arbiter/document.hpp"

namespace arbiter {

namespace {

using Json = nlohmann::json;

// Reads the members of a message, the first one missing or of another kind set as the error
// with its path ("entities[0].arrows[1].pose.position.x: expected a number"); after that every
// read gives a null or 0 and the caller checks ok() when done.
class Fields {
 public:
  explicit Fields(std::string& error) : error_(error) {}
  bool ok() const { return error_.empty(); }
  void fail(std::string message) {
    if (ok()) error_ = std::move(message);
  }

  const Json& member(const Json& object, const std::string& path, const char* key,
                     bool (Json::*is)() const noexcept, const char* what) {
    static const Json kNull;
    if (!ok()) return kNull;
    const auto it = object.find(key);
    if (it == object.end() || !((*it).*is)()) {
      fail(fmt::format("{}{}{}: expected {}", path, path.empty() ? "" : ".", key, what));
      return kNull;
    }
    return *it;
  }
  double number(const Json& object, const std::string& path, const char* key) {
    const Json& value = member(object, path, key, &Json::is_number, "a number");
    return value.is_number() ? value.get<double>() : 0.0;
  }
  const Json& object(const Json& object, const std::string& path, const char* key) {
    return member(object, path, key, &Json::is_object, "an object");
  }
  const Json& array(const Json& object, const std::string& path, const char* key) {
    return member(object, path, key, &Json::is_array, "an array");
  }
  std::string text(const Json& object, const std::string& path, const char* key) {
    const Json& value = member(object, path, key, &Json::is_string, "a string");
    return value.is_string() ? value.get<std::string>() : std::string();
  }

  ScenePoint position(const Json& object, const std::string& path) {
    const auto at = path + ".pose.position";
    const Json& position =
        this->object(this->object(object, path, "pose"), path + ".pose", "position");
    return {number(position, at, "x"), number(position, at, "y")};
  }
  // The turn about the vertical of a pose's orientation (a quaternion about z, as written).
  double yaw(const Json& object, const std::string& path) {
    const Json& orientation =
        this->object(this->object(object, path, "pose"), path + ".pose", "orientation");
    const auto at = path + ".pose.orientation";
    return 2.0 * std::atan2(number(orientation, at, "z"), number(orientation, at, "w"));
  }
  SceneColor color(const Json& object, const std::string& path) {
    const Json& color = this->object(object, path, "color");
    const auto at = path + ".color";
    // Written as the shortest text that reads back as the same float.
    return {static_cast<float>(number(color, at, "r")), static_cast<float>(number(color, at, "g")),
            static_cast<float>(number(color, at, "b")), static_cast<float>(number(color, at, "a"))};
  }

 private:
  std::string& error_;
};

}  // namespace

template <typename Visit>
void RecordedScene::each(const Frame& frame, const std::vector<Entity>& entities, Visit visit) {
  const Entity* parts[2] = {nullptr, nullptr};  // moving, still
  for (std::size_t e = frame.begin; e < frame.end; ++e) {
    parts[entities[e].still ? 1 : 0] = &entities[e];
  }
  std::uint32_t next[2][4] = {}, end[2][4] = {};
  for (std::size_t still = 0; still < 2; ++still) {
    for (std::size_t kind = 0; kind < 4 && parts[still] != nullptr; ++kind) {
      next[still][kind] = parts[still]->kinds[kind];
      end[still][kind] = parts[still]->kinds[kind + 1];
    }
  }
  for (const std::uint8_t slot : frame.order) {
    const std::size_t still = slot % 2, kind = slot / 2;
    if (next[still][kind] < end[still][kind]) {
      visit(*parts[still], parts[still]->primitives[next[still][kind]++]);
    }
  }
  for (const std::size_t still : {1, 0}) {
    for (std::size_t kind = 0; kind < 4; ++kind) {
      while (next[still][kind] < end[still][kind]) {
        visit(*parts[still], parts[still]->primitives[next[still][kind]++]);
      }
    }
  }
}

namespace {

// Where a primitive is in its entity: arrows, filled circles, lines, texts.
std::size_t kind_of(SceneShape shape) {
  switch (shape) {
    case SceneShape::kArrow:
      return 0;
    case SceneShape::kCircle:
      return 1;
    case SceneShape::kText:
      return 3;
    default:
      return 2;
  }
}

// Whether two primitives of entities draw alike, as SceneUpdates compares them.
template <typename Entity, typename Primitive>
bool alike(const Entity& a_entity, const Primitive& a, const Entity& b_entity, const Primitive& b) {
  if (a.shape != b.shape || a.filled != b.filled || a.x0 != b.x0 || a.y0 != b.y0 || a.x1 != b.x1 ||
      a.y1 != b.y1 || a.size != b.size || a.color.r != b.color.r || a.color.g != b.color.g ||
      a.color.b != b.color.b || a.color.a != b.color.a) {
    return false;
  }
  if (a.shape == SceneShape::kText) return a_entity.texts[a.begin] == b_entity.texts[b.begin];
  if (a.shape != SceneShape::kLine && a.shape != SceneShape::kPolygon) return true;
  if (a.count != b.count) return false;
  for (std::uint32_t i = 0; i < a.count; ++i) {
    const ScenePoint& pa = a_entity.points[a.begin + i];
    const ScenePoint& pb = b_entity.points[b.begin + i];
    if (pa.x != pb.x || pa.y != pb.y) return false;
  }
  return true;
}

}  // namespace

bool RecordedScene::apply(const std::string& message, std::string& error) {
  error.clear();
  // nlohmann's parser recurses: a message nested deeper than a recording's never reaches it.
  if (const auto deep = find_too_deep_json(message)) {
    error = fmt::format("nested deeper than {} levels (at byte {} of the message)",
                        ReadLimits().max_depth, *deep);
    return false;
  }
  const auto json = Json::parse(message, nullptr, false);
  if (json.is_discarded() || !json.is_object()) {
    error = "not a JSON object";
    return false;
  }
  Fields read(error);
  std::vector<Entity> next = entities_;
  bool whole = false;  // everything deleted first
  const Json& deletions = read.array(json, "", "deletions");
  for (std::size_t i = 0; read.ok() && i < deletions.size(); ++i) {
    const auto path = fmt::format("deletions[{}]", i);
    const double type = read.number(deletions[i], path, "type");
    if (!read.ok()) break;
    if (type == 1) {  // ALL
      next.clear();
      whole = true;
    } else if (type == 0) {  // MATCHING_ID
      const auto id = read.text(deletions[i], path, "id");
      next.erase(std::remove_if(next.begin(), next.end(),
                                [&](const Entity& entity) { return entity.id == id; }),
                 next.end());
    } else {
      read.fail(fmt::format("{}.type: expected 0 (an id) or 1 (all), not {}", path, type));
    }
  }
  const Json& entities = read.array(json, "", "entities");
  for (std::size_t i = 0; read.ok() && i < entities.size(); ++i) {
    const Json& item = entities[i];
    const auto path = fmt::format("entities[{}]", i);
    Entity entity;
    entity.frame = read.text(item, path, "frame_id");
    entity.id = read.text(item, path, "id");
    if (!read.ok()) break;
    // SceneUpdates' two entities of a frame: what stays put, and what moves.
    if (entity.id == entity.frame + "/still") {
      entity.still = true;
    } else if (entity.id != entity.frame + "/moving") {
      read.fail(fmt::format("{}.id: expected '{}/still' or '{}/moving', not '{}'", path,
                            entity.frame, entity.frame, entity.id));
      break;
    }
    for (const char* none : {"cubes", "spheres", "triangles", "models"}) {
      const auto it = item.find(none);
      if (it != item.end() && !(it->is_array() && it->empty())) {
        read.fail(fmt::format("{}.{}: expected none (a recording draws no {})", path, none, none));
      }
    }
    const Json& arrows = read.array(item, path, "arrows");
    for (std::size_t j = 0; read.ok() && j < arrows.size(); ++j) {
      const auto at = fmt::format("{}.arrows[{}]", path, j);
      Primitive p;
      p.shape = SceneShape::kArrow;
      const ScenePoint from = read.position(arrows[j], at);
      const double yaw = read.yaw(arrows[j], at);
      const double length =
          read.number(arrows[j], at, "shaft_length") + read.number(arrows[j], at, "head_length");
      p.x0 = from.x;
      p.y0 = from.y;
      p.x1 = from.x + length * std::cos(yaw);
      p.y1 = from.y + length * std::sin(yaw);
      p.size = read.number(arrows[j], at, "shaft_diameter");
      p.color = read.color(arrows[j], at);
      entity.primitives.push_back(p);
    }
    entity.kinds[1] = static_cast<std::uint32_t>(entity.primitives.size());
    // Filled circles: flat cylinders, as wide as the circle.
    const Json& cylinders = read.array(item, path, "cylinders");
    for (std::size_t j = 0; read.ok() && j < cylinders.size(); ++j) {
      const auto at = fmt::format("{}.cylinders[{}]", path, j);
      Primitive p;
      p.shape = SceneShape::kCircle;
      p.filled = true;
      const ScenePoint centre = read.position(cylinders[j], at);
      p.x0 = centre.x;
      p.y0 = centre.y;
      p.x1 = 0.02;  // the outline's width, Scene::circle's default: not drawn
      p.size = 0.5 * read.number(read.object(cylinders[j], at, "size"), at + ".size", "x");
      p.color = read.color(cylinders[j], at);
      entity.primitives.push_back(p);
    }
    entity.kinds[2] = static_cast<std::uint32_t>(entity.primitives.size());
    // Lines, polygons, and circles' outlines, which are written as loops of points and are
    // drawn again as such.
    const Json& lines = read.array(item, path, "lines");
    for (std::size_t j = 0; read.ok() && j < lines.size(); ++j) {
      const auto at = fmt::format("{}.lines[{}]", path, j);
      Primitive p;
      const double type = read.number(lines[j], at, "type");
      if (read.ok() && type != 0 && type != 1) {
        read.fail(fmt::format("{}.type: expected 0 (a strip) or 1 (a loop), not {}", at, type));
      }
      p.shape = type == 1 ? SceneShape::kPolygon : SceneShape::kLine;
      p.size = read.number(lines[j], at, "thickness");
      p.color = read.color(lines[j], at);
      const Json& points = read.array(lines[j], at, "points");
      p.begin = static_cast<std::uint32_t>(entity.points.size());
      p.count = static_cast<std::uint32_t>(points.size());
      for (std::size_t k = 0; read.ok() && k < points.size(); ++k) {
        const auto point = fmt::format("{}.points[{}]", at, k);
        entity.points.push_back(
            {read.number(points[k], point, "x"), read.number(points[k], point, "y")});
      }
      entity.primitives.push_back(p);
    }
    entity.kinds[3] = static_cast<std::uint32_t>(entity.primitives.size());
    const Json& texts = read.array(item, path, "texts");
    for (std::size_t j = 0; read.ok() && j < texts.size(); ++j) {
      const auto at = fmt::format("{}.texts[{}]", path, j);
      Primitive p;
      p.shape = SceneShape::kText;
      const ScenePoint where = read.position(texts[j], at);
      p.x0 = where.x;
      p.y0 = where.y;
      p.size = read.number(texts[j], at, "font_size");
      p.color = read.color(texts[j], at);
      p.begin = static_cast<std::uint32_t>(entity.texts.size());
      entity.texts.push_back(read.text(texts[j], at, "text"));
      entity.primitives.push_back(p);
    }
    entity.kinds[4] = static_cast<std::uint32_t>(entity.primitives.size());
    if (!read.ok()) break;
    // In the place a viewer's list of them has: a frame's still entity before its moving one,
    // the frames in the order they came.
    const auto same_id = std::find_if(next.begin(), next.end(),
                                      [&](const Entity& known) { return known.id == entity.id; });
    if (same_id != next.end()) {
      *same_id = std::move(entity);
      continue;
    }
    const auto same_frame = std::find_if(
        next.begin(), next.end(), [&](const Entity& known) { return known.frame == entity.frame; });
    if (same_frame == next.end()) {
      next.push_back(std::move(entity));
    } else {
      next.insert(entity.still ? same_frame : same_frame + 1, std::move(entity));
    }
  }
  if (!read.ok()) return false;

  std::vector<Frame> frames;
  for (std::size_t i = 0; i < next.size(); ++i) {
    if (i > 0 && next[i].frame == next[i - 1].frame) {
      frames.back().end = i + 1;
      continue;
    }
    Frame& frame = frames.emplace_back();
    frame.name = next[i].frame;
    frame.begin = i;
    frame.end = i + 1;
  }
  for (Frame& frame : frames) {
    const auto old = std::find_if(frames_.begin(), frames_.end(),
                                  [&](const Frame& known) { return known.name == frame.name; });
    const Entity* still = nullptr;
    for (std::size_t e = frame.begin; e < frame.end; ++e) {
      if (next[e].still) still = &next[e];
    }
    if (old == frames_.end()) continue;  // the still ones first: at the start, all are
    if (!whole) {
      frame.order = old->order;
      continue;
    }
    // A whole picture: its still primitives are those the recorded run drew alike in the place
    // they had in the step before, which are the places they were drawn in here then. What
    // comes new comes last.
    std::uint32_t next_still[4] = {}, still_end[4] = {}, moving_left[4] = {};
    for (std::size_t kind = 0; kind < 4 && still != nullptr; ++kind) {
      next_still[kind] = still->kinds[kind];
      still_end[kind] = still->kinds[kind + 1];
    }
    for (std::size_t e = frame.begin; e < frame.end; ++e) {
      for (std::size_t kind = 0; kind < 4 && !next[e].still; ++kind) {
        moving_left[kind] = next[e].kinds[kind + 1] - next[e].kinds[kind];
      }
    }
    each(*old, entities_, [&](const Entity& entity, const Primitive& before) {
      const std::size_t kind = kind_of(before.shape);
      const auto slot = static_cast<std::uint8_t>(2 * kind);
      if (next_still[kind] < still_end[kind] &&
          alike(*still, still->primitives[next_still[kind]], entity, before)) {
        frame.order.push_back(slot + 1);
        ++next_still[kind];
      } else if (moving_left[kind] > 0) {
        frame.order.push_back(slot);
        --moving_left[kind];
      } else if (next_still[kind] < still_end[kind]) {
        frame.order.push_back(slot + 1);
        ++next_still[kind];
      }
    });
  }
  entities_ = std::move(next);
  frames_ = std::move(frames);
  return true;
}

void RecordedScene::draw(const StepContext& ctx) const {
  for (const Frame& frame : frames_) {
    Scene scene = ctx.scene(frame.name.c_str());
    each(frame, entities_, [&](const Entity& entity, const Primitive& p) {
      switch (p.shape) {
        case SceneShape::kLine:
          scene.polyline(entity.points.data() + p.begin, p.count, p.color, p.size);
          break;
        case SceneShape::kPolygon:
          scene.polygon(entity.points.data() + p.begin, p.count, p.color, p.size);
          break;
        case SceneShape::kCircle:
          scene.circle({p.x0, p.y0}, p.size, p.color, p.filled, p.x1);
          break;
        case SceneShape::kArrow:
          scene.arrow({p.x0, p.y0}, {p.x1, p.y1}, p.color, p.size);
          break;
        case SceneShape::kText:
          scene.text({p.x0, p.y0}, entity.texts[p.begin].c_str(), p.color, p.size);
          break;
      }
    });
  }
}

}  // namespace arbiter
