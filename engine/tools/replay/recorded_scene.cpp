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
  const Json& deletions = read.array(json, "", "deletions");
  for (std::size_t i = 0; read.ok() && i < deletions.size(); ++i) {
    const auto path = fmt::format("deletions[{}]", i);
    const double type = read.number(deletions[i], path, "type");
    if (!read.ok()) break;
    if (type == 1) {  // ALL
      next.clear();
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
    entity.kinds[0] = 0;
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
  entities_ = std::move(next);
  frames_.clear();
  for (std::size_t i = 0; i < entities_.size(); ++i) {
    if (i > 0 && entities_[i].frame == entities_[i - 1].frame) {
      frames_.back().second = i + 1;
    } else {
      frames_.emplace_back(i, i + 1);
    }
  }
  return true;
}

void RecordedScene::draw(const StepContext& ctx) const {
  for (const auto& [begin, end] : frames_) {
    Scene scene = ctx.scene(entities_[begin].frame.c_str());
    for (std::size_t kind = 0; kind < 4; ++kind) {
      for (std::size_t e = begin; e < end; ++e) {
        const Entity& entity = entities_[e];
        for (auto i = entity.kinds[kind]; i < entity.kinds[kind + 1]; ++i) {
          const Primitive& p = entity.primitives[i];
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
        }
      }
    }
  }
}

}  // namespace arbiter
