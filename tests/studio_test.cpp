// The studio's API (cli/server/studio.cpp, docs/studio.md): operations answer with their edits,
// the new texts and validate's messages and write nothing; Save writes only the config's own
// files, refuses another path (403) and a file changed on the disk since it was opened (409),
// writing nothing then; it writes through a symbolic link, and a new file gets the usual mode;
// over HTTP, the server's token and Origin checks guard it.

#include <httplib.h>
#include <sys/stat.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "arbiter/catalog.hpp"
#include "server/serve.hpp"
#include "server/studio.hpp"
#include "test_support.hpp"

using namespace arbiter;
using namespace arbiter::cli;
using namespace arbiter::test;
using Json = nlohmann::json;

namespace {

std::string read(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

std::string config_copy(const TempDir& dir) {
  return dir.write("robot.yaml", read(ARBITER_SOURCE_DIR "/configs/paper/walk_and_kick.yaml"));
}

/// The studio on a copy of the paper's walk_and_kick config, as most cases start.
struct StudioOnACopy {
  TempDir dir;
  std::string path = config_copy(dir);
  Registry registry = make_test_registry();
  Studio studio{path, registry, with_lints()};
};

/// The save request for the studio's texts as they are now.
std::string save_body(const Json& state) {
  Json files = Json::array();
  for (const auto& file : state["files"]) {
    files.push_back({{"path", file["path"]}, {"text", file["text"]}, {"base", file["base"]}});
  }
  return Json{{"files", files}}.dump();
}

}  // namespace

TEST_CASE_METHOD(
    StudioOnACopy,
    "a studio operation answers with its edits, the texts and the diagnostics, and writes "
    "nothing",
    "[studio]") {
  const std::string original = read(path);

  const auto [status, body] = studio.edit(
      R"({"op": "add_inhibition", "layer": "control", "inhibitor": "kick_ball",
          "inhibited": "search_for_ball", "chaining": false})");
  REQUIRE(status == 200);
  const Json reply = Json::parse(body);
  REQUIRE(reply["edits"].size() == 1);
  CHECK(reply["edits"][0]["text"] == "      - kick_ball -> search_for_ball\n");
  const std::string text = reply["files"][0]["text"];
  CHECK(contains(text,
                 "      - search_for_ball -> head_control\n"
                 "      - kick_ball -> search_for_ball\n"));
  CHECK(reply["files"][0]["edited"] == true);
  CHECK(reply["review"] == "+ inhibition control: kick_ball -> search_for_ball\n");
  // The graph of the edited texts.
  bool drawn = false;
  for (const auto& inhibition : reply["graph"]["layers"][0]["inhibitions"]) {
    drawn = drawn || (inhibition["inhibitor"] == "kick_ball" &&
                      inhibition["inhibited"] == "search_for_ball" && !inhibition["implicit"]);
  }
  CHECK(drawn);
  CHECK(read(path) == original);

  // Then flipped, and the rename follows every reference.
  REQUIRE(studio
              .edit(R"({"op": "flip_chaining", "layer": "control", "inhibitor": "kick_ball",
                        "inhibited": "search_for_ball"})")
              .first == 200);
  const auto renamed = studio.edit(
      R"({"op": "rename", "kind": "behaviour", "scope": "control", "name": "head_control",
          "to": "look_around"})");
  REQUIRE(renamed.first == 200);
  const std::string after = Json::parse(renamed.second)["files"][0]["text"];
  CHECK(contains(after, "      - kick_ball => search_for_ball\n"));
  CHECK(contains(after, "      look_around:\n"));
  CHECK(contains(after, "      - search_for_ball -> look_around\n"));
  CHECK(!contains(after, "head_control"));
  CHECK(read(path) == original);
}

TEST_CASE_METHOD(StudioOnACopy,
                 "a studio edit that validate would reject is refused with validate's message",
                 "[studio]") {
  const auto [status, body] = studio.edit(
      R"({"op": "set_param", "layer": "control", "behaviour": "head_control",
          "param": "activation", "value": 3})");
  CHECK(status == 422);
  const Json reply = Json::parse(body);
  CHECK(contains(reply["refused"],
                 "param 'activation' of behaviour 'head_control' is 3; it must "
                 "be a number in [0, 1]"));
  CHECK(reply["files"][0]["edited"] == false);

  CHECK(
      studio.edit(R"({"op": "rename", "kind": "behaviour", "name": "nobody", "to": "x"})").first ==
      422);
  CHECK(studio.edit(R"({"op": "explode"})").first == 400);
  CHECK(studio.edit(R"({"op": "add_inhibition", "layer": "control"})").first == 400);
  CHECK(studio.edit("not json").first == 400);
  // An optional member of the wrong type is named, not thrown on.
  const auto mistyped = studio.edit(
      R"({"op": "add_inhibition", "layer": "control", "inhibitor": "kick_ball",
          "inhibited": "head_control", "chaining": "yes"})");
  CHECK(mistyped.first == 400);
  CHECK(Json::parse(mistyped.second)["error"] ==
        "add_inhibition's 'chaining' is not true or false");

  // A text that does not parse is held all the same, with its errors and no graph.
  const auto broken = studio.set_texts(Json{{"texts", {{path, "layers: [\n"}}}}.dump());
  REQUIRE(broken.first == 200);
  const Json state = Json::parse(broken.second);
  CHECK(state["graph"].is_null());
  CHECK(!state["diagnostics"].empty());
  CHECK(state["files"][0]["text"] == "layers: [\n");
}

TEST_CASE(
    "studio save writes only the config's own files, atomically, and never over a change "
    "made on the disk",
    "[studio]") {
  TempDir dir;
  const std::string path = config_copy(dir);
  const std::string original = read(path);
  const std::string other = dir.write("other.yaml", "kept: true\n");
  Registry registry = make_test_registry();
  Studio studio(path, registry, with_lints());
  const auto edited = studio.edit(
      R"({"op": "set_param", "layer": "control", "behaviour": "head_control",
          "param": "activation", "value": 0.5})");
  REQUIRE(edited.first == 200);
  const Json state = Json::parse(edited.second);

  // Another file, by any name, is refused, and nothing is written, the config's own included.
  for (const std::string& name :
       {other, dir.file("new.yaml"), dir.file("./robot.yaml"), std::string("/etc/hostname")}) {
    Json body = Json::parse(save_body(state));
    body["files"].push_back({{"path", name}, {"text", "x: 1\n"}, {"base", read(name)}});
    INFO(name);
    const auto [status, reply] = studio.save(body.dump());
    CHECK(status == 403);
    CHECK(contains(reply, "is not one of the config's files"));
  }
  CHECK(read(other) == "kept: true\n");
  CHECK(!std::filesystem::exists(dir / "new.yaml"));
  CHECK(read(path) == original);

  // A change on the disk since the studio read the file: a conflict, never overwritten.
  std::ofstream(path, std::ios::binary) << original << "# changed by hand\n";
  const auto conflict = studio.save(save_body(state));
  CHECK(conflict.first == 409);
  CHECK(contains(conflict.second, "changed on the disk"));
  CHECK(read(path) == original + "# changed by hand\n");
  CHECK(Json::parse(studio.state().second)["files"][0]["changed_on_disk"] == true);

  // Reloaded from the disk, the change made there is the new base, and the edits are gone.
  const Json reverted = Json::parse(studio.revert().second);
  CHECK(reverted["files"][0]["text"] == original + "# changed by hand\n");
  CHECK(reverted["files"][0]["edited"] == false);
  CHECK(reverted["files"][0]["changed_on_disk"] == false);

  std::ofstream(path, std::ios::binary) << original;
  const auto saved = studio.save(save_body(state));
  REQUIRE(saved.first == 200);
  CHECK(read(path) == state["files"][0]["text"]);
  const Json after = Json::parse(saved.second);
  CHECK(after["files"][0]["edited"] == false);
  CHECK(after["review"] == "");  // nothing left to save
  // The temporary file was renamed over the config: none is left beside it.
  std::size_t entries = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    (void)entry;
    ++entries;
  }
  CHECK(entries == 2);
}

TEST_CASE_METHOD(
    StudioOnACopy,
    "the studio's API over HTTP needs the token, and edits and saves need its own origin",
    "[studio]") {
  const std::string original = read(path);
  WebServer server;
  studio.attach(server.http());
  std::string error;
  REQUIRE(server.start(ServeAddress{}, LiveAccess{"studio-token", false}, error));
  const std::string url = server.url();
  const int port = std::stoi(url.substr(url.rfind(':') + 1));
  httplib::Client client("127.0.0.1", port);
  const httplib::Headers token{{"X-Arbiter-Token", "studio-token"}};
  const std::string origin = "http://127.0.0.1:" + std::to_string(port);

  CHECK(client.Get("/studio/state")->status == 403);
  const auto state = client.Get("/studio/state", token);
  REQUIRE(state);
  REQUIRE(state->status == 200);
  Json body = Json::parse(save_body(Json::parse(state->body)));
  body["files"][0]["text"] = "arbiter: 1\nname: overwritten\n";
  const std::string save = body.dump();
  CHECK(client.Post("/studio/save", save, "application/json")->status == 403);
  CHECK(client
            .Post("/studio/save",
                  {{"X-Arbiter-Token", "studio-token"}, {"Origin", "http://evil.example"}}, save,
                  "application/json")
            ->status == 403);
  CHECK(client
            .Post("/studio/save",
                  {{"X-Arbiter-Token", "studio-token"}, {"Sec-Fetch-Site", "cross-site"}}, save,
                  "application/json")
            ->status == 403);
  CHECK(client
            .Post("/studio/edit",
                  {{"X-Arbiter-Token", "studio-token"}, {"Origin", "http://evil.example"}},
                  R"({"op": "remove_inhibition", "layer": "control", "inhibitor": "kick_ball",
                        "inhibited": "go_behind_ball"})",
                  "application/json")
            ->status == 403);
  CHECK(read(path) == original);
  const auto own =
      client.Post("/studio/save", {{"X-Arbiter-Token", "studio-token"}, {"Origin", origin}}, save,
                  "application/json");
  REQUIRE(own);
  CHECK(own->status == 200);
  CHECK(read(path) == "arbiter: 1\nname: overwritten\n");
  server.stop();
}

TEST_CASE(
    "the studio edits an included file where it declares the element, and a JSON config "
    "as JSON",
    "[studio]") {
  TempDir dir;
  const std::string main_text = R"(arbiter: 1
name: included
include: [parts/control.yaml]
layers:
  - name: top
    behaviours:
      watch: scripted
)";
  const std::string part_text = R"(# The control layer, in a file of its own.
layers:
  - name: control
    behaviours:
      a: scripted
      b: scripted
    inhibitions:
      - a => b
)";
  const std::string main = dir.write("main.yaml", main_text);
  std::filesystem::create_directories(dir / "parts");
  const std::string part = dir.write("parts/control.yaml", part_text);
  Registry registry = make_test_registry();
  Studio studio(main, registry, with_lints());
  const Json opened = Json::parse(studio.state().second);
  REQUIRE(opened["files"].size() == 2);
  const std::string part_path = opened["files"][1]["path"];
  CHECK(std::filesystem::equivalent(part_path, part));

  const auto renamed = studio.edit(
      R"({"op": "rename", "kind": "behaviour", "scope": "control", "name": "b", "to": "c"})");
  REQUIRE(renamed.first == 200);
  const auto [status, body] = studio.edit(
      R"({"op": "set_param", "layer": "control", "behaviour": "a", "param": "activation",
          "value": 0.5})");
  REQUIRE(status == 200);
  const Json state = Json::parse(body);
  CHECK(state["edits"][0]["file"] == part_path);
  CHECK(state["files"][0]["edited"] == false);
  CHECK(state["files"][1]["text"] == R"(# The control layer, in a file of its own.
layers:
  - name: control
    behaviours:
      a: {type: scripted, params: {activation: 0.5}}
      c: scripted
    inhibitions:
      - a => c
)");
  REQUIRE(studio.save(save_body(state)).first == 200);
  CHECK(read(main) == main_text);
  CHECK(read(part) == state["files"][1]["text"]);

  // The include taken out of the text: the studio still holds the part's text, but the config no
  // longer reads it, and Save refuses to write it.
  std::string without = main_text;
  without.replace(without.find("include: [parts/control.yaml]\n"), 30, "");
  REQUIRE(studio.set_texts(Json{{"texts", {{main, without}}}}.dump()).first == 200);
  const std::string part_saved = read(part);
  const Json stray = {
      {"files",
       Json::array({{{"path", part_path}, {"text", "OVERWRITTEN\n"}, {"base", part_saved}}})}};
  const auto refused = studio.save(stray.dump());
  CHECK(refused.first == 403);
  CHECK(contains(refused.second, "is not one of the config's files"));
  CHECK(read(part) == part_saved);

  // JSON: the inhibition as a JSON string, the param as a JSON member; the result loads.
  const std::string json =
      dir.write("robot.json", read(ARBITER_SOURCE_DIR "/configs/paper/walk_and_kick.json"));
  Studio json_studio(json, registry, with_lints());
  REQUIRE(json_studio
              .edit(R"({"op": "add_inhibition", "layer": "control", "inhibitor": "kick_ball",
                        "inhibited": "head_control", "chaining": false})")
              .first == 200);
  const auto set = json_studio.edit(
      R"({"op": "set_param", "layer": "control", "behaviour": "head_control",
          "param": "activation", "value": 0.25})");
  REQUIRE(set.first == 200);
  const Json after = Json::parse(set.second);
  const std::string text = after["files"][0]["text"];
  CHECK(contains(text, R"("search_for_ball -> head_control", "kick_ball -> head_control")"));
  CHECK(Json::parse(text).is_object());
  CHECK(!after["graph"].is_null());
  CHECK(after["review"] ==
        "+ inhibition control: kick_ball -> head_control\n"
        "~ behaviour control/head_control: params: activation [1.0] -> [0.25]\n");
}

TEST_CASE_METHOD(StudioOnACopy,
                 "the studio moves a behaviour and a layer, and refuses a move it cannot make",
                 "[studio]") {
  const std::string original = read(path);

  const auto moved =
      studio.edit(R"({"op": "move_behaviour", "layer": "control", "name": "head_control",
                      "index": 0})");
  REQUIRE(moved.first == 200);
  const Json reply = Json::parse(moved.second);
  const std::string text = reply["files"][0]["text"];
  CHECK(contains(text, "    behaviours:\n      head_control:\n        type: scripted\n"));
  CHECK(reply["files"][0]["edited"] == true);
  CHECK(read(path) == original);

  const auto layer = studio.edit(R"({"op": "move_layer", "layer": "control", "index": 0})");
  CHECK(layer.first == 422);
  CHECK(Json::parse(layer.second)["refused"] == "layer 'control' is at position 0 already");
  const auto across =
      studio.edit(R"({"op": "move_behaviour", "layer": "control", "name": "kick_ball",
                      "to_layer": "control", "index": 9})");
  CHECK(across.first == 422);
  CHECK(contains(Json::parse(across.second)["refused"], "position 9 is past the end"));
  const auto no_index =
      studio.edit(R"({"op": "move_behaviour", "layer": "control", "name": "kick_ball",
                      "index": -1})");
  CHECK(no_index.first == 400);
  CHECK(contains(no_index.second,
                 "move_behaviour needs 'index' (names as strings, positions as integers from 0)"));
}

TEST_CASE_METHOD(
    StudioOnACopy,
    "the studio adds and removes an actuator and wires a port, refusing a used actuator",
    "[studio]") {
  const auto used = studio.edit(R"({"op": "remove_actuator", "layer": "control", "name": "kick"})");
  CHECK(used.first == 422);
  // A scripted behaviour's writes: are not a binding the engine follows: validate's words say it.
  CHECK(contains(Json::parse(used.second)["refused"], "kick"));

  const auto added = studio.edit(
      R"({"op": "add_actuator", "layer": "control", "name": "probe_out", "type": "double"})");
  REQUIRE(added.first == 200);
  CHECK(contains(Json::parse(added.second)["files"][0]["text"],
                 "      kick: {type: bool}\n      probe_out: {type: double}\n"));
  REQUIRE(studio
              .edit(R"({"op": "add_behaviour", "layer": "control", "name": "probe",
                        "type": "test.Probe"})")
              .first == 200);
  const auto wired = studio.edit(
      R"({"op": "wire_port", "layer": "control", "behaviour": "probe", "port": "out",
          "target": "probe_out"})");
  REQUIRE(wired.first == 200);
  const Json state = Json::parse(wired.second);
  CHECK(contains(state["files"][0]["text"],
                 "      probe: {type: test.Probe, ports: {out: probe_out}}\n"));
  const auto still =
      studio.edit(R"({"op": "remove_actuator", "layer": "control", "name": "probe_out"})");
  CHECK(still.first == 422);
  CHECK(Json::parse(still.second)["refused"] ==
        "actuator 'probe_out' is still used: port 'out' of 'probe' is bound to it. Remove or "
        "rebind those first");
  CHECK(studio.edit(R"({"op": "wire_port", "layer": "control", "behaviour": "probe"})").first ==
        400);
}

TEST_CASE("the studio's state offers the plugins on the plugin path that the config does not name",
          "[studio]") {
  TempDir dir;
  const std::string path = config_copy(dir);
  Registry registry = make_test_registry();
  LoadOptions options = with_lints();
  options.plugins.path = {ARBITER_PLUGIN_DIR};
  options.plugins.use_environment = false;
  options.plugins.use_default_path = false;
  Studio studio{path, registry, options};

  // The build's plugins: soccer, and the DDS bridge when it is built.
  std::vector<std::string> on_path = plugins_on_path(options.plugins);
  REQUIRE(std::find(on_path.begin(), on_path.end(), "soccer") != on_path.end());
  CHECK(Json::parse(studio.state().second)["plugins_to_add"] == Json(on_path));
  const auto [status, body] = studio.edit(R"({"op": "add_plugin", "name": "soccer"})");
  REQUIRE(status == 200);
  on_path.erase(std::find(on_path.begin(), on_path.end(), "soccer"));
  CHECK(Json::parse(body)["plugins_to_add"] == Json(on_path));
}

TEST_CASE("the studio edits a state machine's queue: a state planned with params, moved, removed",
          "[studio]") {
  TempDir dir;
  const std::string path =
      dir.write("plan.yaml", read(ARBITER_SOURCE_DIR "/configs/paper/goalie_plan.yaml"));
  Registry registry = make_test_registry();
  Studio studio(path, registry, with_lints());
  const std::string queue =
      "    queue:\n"
      "      - wait_for_button\n"
      "      - walk_to_pose: {hold: 6}   # into the goal: (0.0, -4.2, 1.57)\n"
      "      - obstacle_ahead\n"
      "      - monitor_ball\n";
  REQUIRE(contains(Json::parse(studio.state().second)["files"][0]["text"], queue));

  const auto added = studio.edit(
      R"({"op": "add_queue_entry", "machine": "goalie", "state": "walk_to_pose",
          "params": {"hold": 2}})");
  REQUIRE(added.first == 200);
  CHECK(Json::parse(added.second)["edits"][0]["text"] == "\n      - walk_to_pose: {hold: 2}");
  const auto moved =
      studio.edit(R"({"op": "move_queue_entry", "machine": "goalie", "from": 1, "to": 0})");
  REQUIRE(moved.first == 200);
  const auto removed =
      studio.edit(R"({"op": "remove_queue_entry", "machine": "goalie", "index": 2})");
  REQUIRE(removed.first == 200);
  CHECK(contains(Json::parse(removed.second)["files"][0]["text"],
                 "    queue:\n"
                 "      - walk_to_pose: {hold: 6}   # into the goal: (0.0, -4.2, 1.57)\n"
                 "      - wait_for_button\n"
                 "      - monitor_ball\n"
                 "      - walk_to_pose: {hold: 2}\n"));

  const auto unknown = studio.edit(
      R"({"op": "add_queue_entry", "machine": "goalie", "state": "celebrate", "index": 0})");
  CHECK(unknown.first == 422);
  CHECK(contains(Json::parse(unknown.second)["refused"], "celebrate"));

  // The state declared, then planned; a state still planned is not removed.
  REQUIRE(studio
              .edit(R"({"op": "add_state", "machine": "goalie", "name": "celebrate",
                        "type": "scripted"})")
              .first == 200);
  const auto planned = studio.edit(
      R"({"op": "add_queue_entry", "machine": "goalie", "state": "celebrate", "index": 0})");
  REQUIRE(planned.first == 200);
  CHECK(contains(Json::parse(planned.second)["files"][0]["text"],
                 "      celebrate: {type: scripted}\n    queue:\n      - celebrate\n"));
  const auto named =
      studio.edit(R"({"op": "remove_state", "machine": "goalie", "name": "celebrate"})");
  CHECK(named.first == 422);
  CHECK(contains(Json::parse(named.second)["refused"],
                 "state 'celebrate' of state machine 'goalie' is still named at "));
  REQUIRE(studio.edit(R"({"op": "remove_queue_entry", "machine": "goalie", "index": 0})").first ==
          200);
  const auto removed_state =
      studio.edit(R"({"op": "remove_state", "machine": "goalie", "name": "celebrate"})");
  REQUIRE(removed_state.first == 200);
  CHECK(!contains(Json::parse(removed_state.second)["files"][0]["text"], "celebrate"));
  CHECK(studio.edit(R"({"op": "move_queue_entry", "machine": "goalie", "from": 1})").first == 400);
  CHECK(studio
            .edit(R"({"op": "add_queue_entry", "machine": "goalie", "state": "dive",
                        "params": [1]})")
            .first == 400);
}

TEST_CASE_METHOD(StudioOnACopy,
                 "the studio adds and removes a layer and a state machine, refusing a name taken",
                 "[studio]") {
  const auto added = studio.edit(R"({"op": "add_layer", "name": "io", "interface": "inputs"})");
  REQUIRE(added.first == 200);
  CHECK(Json::parse(added.second)["edits"][0]["text"] == "\n  - name: io\n    interface: inputs");
  const auto first = studio.edit(R"({"op": "add_layer", "name": "plan", "index": 0})");
  REQUIRE(first.first == 200);
  const Json layers = Json::parse(first.second)["graph"]["layers"];
  REQUIRE(layers.size() == 3);
  CHECK(layers[0]["name"] == "plan");
  CHECK(layers[2]["name"] == "io");
  REQUIRE(studio.edit(R"({"op": "remove_layer", "name": "plan"})").first == 200);
  const auto taken = studio.edit(R"({"op": "add_layer", "name": "control"})");
  CHECK(taken.first == 422);
  CHECK(Json::parse(taken.second)["refused"] ==
        "'control' is already taken: a layer of that name is declared");
  CHECK(studio.edit(R"({"op": "add_layer", "name": "x", "index": "0"})").first == 400);

  const auto machine = studio.edit(R"({"op": "add_state_machine", "name": "plan"})");
  REQUIRE(machine.first == 200);
  CHECK(contains(Json::parse(machine.second)["files"][0]["text"],
                 "state_machines:\n  plan:\n    states: {}\n    queue: []\n"));
  const auto again = studio.edit(R"({"op": "add_state_machine", "name": "plan"})");
  CHECK(again.first == 422);
  CHECK(Json::parse(again.second)["refused"] ==
        "'plan' is already taken: a state machine of that name is declared");
  // A layer that reads another's actuator: the sensor added, the reader refused its removal.
  REQUIRE(studio.edit(R"({"op": "add_sensor", "layer": "io", "name": "kick"})").first == 200);
  const auto read_by = studio.edit(R"({"op": "remove_layer", "name": "control"})");
  CHECK(read_by.first == 422);
  CHECK(Json::parse(read_by.second)["refused"] ==
        "layer 'control' is still used: layer 'io' reads its actuator 'kick'. Remove those "
        "sensors first");
  const auto unread = studio.edit(R"({"op": "remove_sensor", "layer": "io", "name": "kick"})");
  REQUIRE(unread.first == 200);
  CHECK(contains(Json::parse(unread.second)["files"][0]["text"],
                 "  - name: io\n    interface: inputs\n    sensors: []\n"));
  const auto no_plugin = studio.edit(R"({"op": "add_plugin", "name": "no_such_plugin"})");
  CHECK(no_plugin.first == 422);
  CHECK(contains(Json::parse(no_plugin.second)["refused"], "no_such_plugin"));
  CHECK(studio.edit(R"({"op": "add_sensor", "layer": "io"})").first == 400);

  const auto removed = studio.edit(R"({"op": "remove_state_machine", "name": "plan"})");
  REQUIRE(removed.first == 200);
  CHECK(!contains(Json::parse(removed.second)["files"][0]["text"], "state_machines"));
}

TEST_CASE("the studio opens a config that does not exist yet as a valid one, written on save",
          "[studio]") {
  TempDir dir;
  const std::string path = dir.file("My-Robot.yaml");
  Registry registry = make_test_registry();
  Studio studio(path, registry, with_lints());
  const Json state = Json::parse(studio.state().second);
  REQUIRE(state["files"].size() == 1);
  CHECK(state["files"][0]["path"] == path);
  CHECK(state["files"][0]["text"] == "arbiter: 1\nname: my_robot\nlayers: []\n");
  CHECK(state["files"][0]["base"] == "");
  CHECK(state["files"][0]["changed_on_disk"] == false);
  CHECK(state["diagnostics"].empty());
  CHECK_FALSE(std::filesystem::exists(path));  // nothing written on open

  REQUIRE(studio.edit(R"({"op": "add_layer", "name": "control"})").first == 200);
  const auto saved = studio.save(save_body(Json::parse(studio.state().second)));
  REQUIRE(saved.first == 200);
  CHECK(read(path) == "arbiter: 1\nname: my_robot\nlayers:\n  - name: control\n");

  // An empty file opens the same way; a JSON one as JSON.
  const std::string json = dir.write("9lives.json", "\n");
  Studio empty(json, registry, with_lints());
  const Json json_state = Json::parse(empty.state().second);
  CHECK(json_state["files"][0]["text"] ==
        "{\n  \"arbiter\": 1,\n  \"name\": \"_9lives\",\n  \"layers\": []\n}\n");
  CHECK(json_state["files"][0]["base"] == "\n");
  CHECK(json_state["diagnostics"].empty());
}

TEST_CASE(
    "the studio's save refuses the config when it holds no text of it (its load could not "
    "read it)",
    "[studio]") {
  // The config's load reads it under the read limits: one too big is reported and not read, so
  // the studio holds no text of it and shows none, though it is the config. A save of it (a
  // request the page does not make) is refused: it would write a file the studio never showed.
  TempDir dir;
  const std::string text = "arbiter: 1\nname: big\nlayers: []\n# " + std::string(200, 'x') + "\n";
  const std::string path = dir.write("robot.yaml", text);
  Registry registry = make_test_registry();
  LoadOptions options = with_lints();
  options.limits.max_file_bytes = 64;
  Studio studio(path, registry, options);
  const Json state = Json::parse(studio.state().second);
  CHECK(state["files"].empty());
  const Json body = {
      {"files", Json::array({{{"path", path}, {"text", "arbiter: 1\n"}, {"base", text}}})}};
  const auto [status, reply] = studio.save(body.dump());
  CHECK(status == 403);
  CHECK(contains(reply, "is not one of the config's files"));
  CHECK(read(path) == text);
}

TEST_CASE("the studio's save writes through a symbolic link, which stays a link", "[studio]") {
  TempDir dir;
  const std::string real = config_copy(dir);
  const std::string link = dir.file("link.yaml");
  std::filesystem::create_symlink("robot.yaml", link);
  Registry registry = make_test_registry();
  Studio studio(link, registry, with_lints());
  REQUIRE(studio
              .edit(R"({"op": "add_inhibition", "layer": "control", "inhibitor": "kick_ball",
                        "inhibited": "search_for_ball", "chaining": false})")
              .first == 200);
  REQUIRE(studio.save(save_body(Json::parse(studio.state().second))).first == 200);

  CHECK(std::filesystem::is_symlink(link));
  CHECK(contains(read(real), "      - kick_ball -> search_for_ball\n"));
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  CHECK(names == std::vector<std::string>{"link.yaml", "robot.yaml"});  // no temporary file left
}

TEST_CASE(
    "a file the studio's save creates gets the mode of any new file, one it replaces keeps "
    "its own",
    "[studio]") {
  TempDir dir;
  Registry registry = make_test_registry();
  const std::string created = dir.file("robot.yaml");
  const std::string kept = dir.write("kept.yaml", "arbiter: 1\nname: kept\nlayers: []\n");
  std::filesystem::permissions(kept, std::filesystem::perms(0640));
  const ::mode_t umask = ::umask(022);
  for (const auto& path : {created, kept}) {
    Studio studio(path, registry, with_lints());
    REQUIRE(studio.edit(R"({"op": "add_layer", "name": "control"})").first == 200);
    REQUIRE(studio.save(save_body(Json::parse(studio.state().second))).first == 200);
  }
  ::umask(umask);
  CHECK(std::filesystem::status(created).permissions() == std::filesystem::perms(0644));
  CHECK(std::filesystem::status(kept).permissions() == std::filesystem::perms(0640));
  CHECK(contains(read(kept), "  - name: control\n"));
}
