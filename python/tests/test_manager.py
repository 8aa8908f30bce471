"""Manager: a program stepped from Python; levels, actuators and states read; inputs written;
pause and reload."""

import json

import pytest

import arbiter

INPUTS_CONFIG = """\
arbiter: 1
name: fed
layers:
  - name: world
    interface: inputs
    actuators:
      ball_visible: {type: bool}
      ball_position: {type: vec2}
  - name: control
    sensors: [ball_visible]
    actuators:
      kick: {type: bool, safe: false}
      speed: {type: double, aggregate: true, safe: 0.0}
    behaviours:
      kick_ball: {type: scripted, params: {activation: KICK, writes: {kick: true, speed: 1.5}}}
      walk: {type: scripted, params: {activation: 1, writes: {speed: 0.5}}}
    inhibitions:
      - kick_ball => walk
"""


def write_config(tmp_path, kick="[0, 1, 1, 0]"):
    config = tmp_path / "fed.yaml"
    config.write_text(INPUTS_CONFIG.replace("KICK", kick))
    return config


@pytest.fixture
def walk_and_kick(source):
    return arbiter.load(source / "configs/paper/walk_and_kick.yaml").manager()


def test_levels_after_each_step_are_the_papers(walk_and_kick):
    walk_and_kick.step(5)
    # Step 5: go_behind_ball requests 0.3 and inhibits search_for_ball (0.5) by chaining.
    assert walk_and_kick.levels("go_behind_ball") == {
        "activation": 0.3, "requested": 0.3, "active": True}
    assert walk_and_kick.activation("search_for_ball") == pytest.approx(0.5 * 0.7)
    assert walk_and_kick.requested("control/search_for_ball") == 0.5
    assert walk_and_kick.steps == 5
    walk_and_kick.step(8)
    assert walk_and_kick.active("kick_ball")
    assert not walk_and_kick.active("go_behind_ball")
    assert set(walk_and_kick.all_levels()) == {
        "control/kick_ball", "control/go_behind_ball", "control/search_for_ball",
        "control/head_control"}


def test_actuators_read_as_python_values(walk_and_kick):
    walk_and_kick.step(13)
    assert walk_and_kick.actuator("kick") is True
    assert walk_and_kick.actuator("gait_velocity") == (0.3, 0.1, 0.0)
    assert walk_and_kick.actuators() == {
        "gait_velocity": (0.3, 0.1, 0.0), "head_angle": -0.5, "kick": True}


def test_unknown_names_are_key_errors_with_suggestions(walk_and_kick):
    with pytest.raises(KeyError, match="did you mean 'kick_ball'"):
        walk_and_kick.levels("kick_bal")
    with pytest.raises(KeyError, match="did you mean 'kick'"):
        walk_and_kick.actuator("kik")
    with pytest.raises(KeyError, match="no state machine 'goalie'"):
        walk_and_kick.state("goalie")


def test_state_machines_current_states_follow_the_plan(source):
    manager = arbiter.load(source / "configs/paper/goalie_plan.yaml").manager()
    assert manager.state("goalie") is None
    manager.step()
    assert manager.state("goalie") == "wait_for_button"
    manager.step(5)
    assert manager.states() == {"goalie": "walk_to_pose"}
    assert manager.status("goalie") == "running"


def test_inputs_written_from_python_reach_the_actuators(tmp_path):
    manager = arbiter.load(write_config(tmp_path)).manager()
    assert manager.inputs == ["ball_position", "ball_visible"]
    manager.step()
    assert manager.actuator("ball_position") == (0.0, 0.0)
    manager.set_input("ball_position", [1.5, -0.25])
    manager.set_input("ball_visible", True)
    manager.step()
    assert manager.actuator("ball_position") == (1.5, -0.25)
    assert manager.actuator("ball_visible") is True


def test_a_wrong_input_is_an_error_naming_it(tmp_path):
    manager = arbiter.load(write_config(tmp_path)).manager()
    with pytest.raises(TypeError, match="value for 'ball_position' has type vec2: it needs a list "
                                        "of 2 finite numbers"):
        manager.set_input("ball_position", [1.0])
    with pytest.raises(TypeError, match="value for 'ball_visible' .* must be a JSON value"):
        manager.set_input("ball_visible", object())
    with pytest.raises(KeyError, match="did you mean 'ball_visible'"):
        manager.set_input("ball_visibel", True)


def test_wrong_argument_types_name_the_parameter(walk_and_kick):
    with pytest.raises(TypeError, match="count: int"):
        walk_and_kick.step("3")
    with pytest.raises(TypeError, match="behaviour: str"):
        walk_and_kick.levels(3)


def test_pause_outputs_the_safe_values_and_resume_goes_on(tmp_path):
    manager = arbiter.load(write_config(tmp_path)).manager()
    manager.step(2)
    assert manager.actuator("kick") is True
    assert manager.actuator("speed") == 1.5
    manager.pause()
    assert manager.paused
    assert manager.actuator("kick") is False
    assert manager.actuator("speed") == 0.0
    manager.step()  # a single step while paused ends on the safe values again
    assert manager.steps == 3
    assert manager.actuator("speed") == 0.0
    manager.resume()
    manager.step()
    assert manager.actuator("speed") == 0.5


def test_reload_swaps_the_edited_config_in_at_the_next_step(tmp_path):
    config = write_config(tmp_path, kick="0")
    manager = arbiter.load(config).manager()
    manager.set_input("ball_visible", True)
    manager.step(2)
    assert not manager.active("kick_ball")
    write_config(tmp_path, kick="1")
    result = manager.reload()
    assert [change.split(":")[0] for change in result["changes"]] == [
        "~ behaviour control/kick_ball"]
    manager.step()
    assert manager.active("kick_ball")
    assert manager.steps == 3
    assert manager.actuator("ball_visible") is True, "inputs survive a reload"


def test_a_reload_with_errors_leaves_the_run_untouched(tmp_path):
    config = write_config(tmp_path, kick="1")
    manager = arbiter.load(config).manager()
    manager.step()
    config.write_text(config.read_text().replace("kick_ball => walk", "kick_ball => wlak"))
    with pytest.raises(arbiter.ConfigError) as raised:
        manager.reload()
    assert raised.value.diagnostics[0].code == "unknown-behaviour"
    manager.step()
    assert manager.active("kick_ball") and not manager.active("walk")


def test_a_trace_records_every_step(tmp_path, walk_and_kick):
    walk_and_kick.trace(tmp_path / "run.jsonl")
    walk_and_kick.step(3)
    walk_and_kick.finish()
    lines = (tmp_path / "run.jsonl").read_text().splitlines()
    assert json.loads(lines[0])["arbiter_trace"] == 1
    assert [json.loads(line)["step"] for line in lines[1:4]] == [1, 2, 3]
