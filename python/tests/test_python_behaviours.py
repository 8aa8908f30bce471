"""Behaviour classes written in Python: registered from `plugins: [{python: MODULE}]`, checked
like C++ classes, mixed with them, their exceptions handled as C++ faults."""

import pytest

import arbiter

KICK_MODULE = '''
import arbiter


class KickBall(arbiter.Behaviour):
    """Kicks when the ball is seen within `distance` metres."""

    name = "py.KickBall"
    params = {"distance": 0.3, "strength": float}
    inputs = {"ball_position": "vec2", "ball_visible": "bool"}
    outputs = {"kick": "bool"}

    def activation(self, ctx):
        x, y = ctx.read("ball_position")
        close = (x * x + y * y) ** 0.5 < self.distance
        return 1.0 if ctx.read("ball_visible") and close else 0.0

    def execute(self, ctx):
        ctx.write("kick", True)
'''

FAULTY_MODULE = '''
import arbiter


class Faulty(arbiter.Behaviour):
    name = "py.Faulty"
    outputs = {"speed": "double"}

    def activation(self, ctx):
        return 1.0

    def execute(self, ctx):
        if ctx.step == 3:
            raise RuntimeError("lost the ball")
        ctx.write("speed", 1.0)
'''

FAULTY_CONFIG = """\
arbiter: 1
name: faulty
plugins: [{python: faulty}]
POLICY
layers:
  - name: control
    actuators:
      speed: {type: double, aggregate: true}
    behaviours:
      faulty: {type: py.Faulty}
      walk: {type: scripted, params: {activation: 0.5, writes: {speed: 0.2}}}
"""


@pytest.fixture
def soccer_with_python_kick(tmp_path, source):
    (tmp_path / "py_kick.py").write_text(KICK_MODULE)
    config = (source / "configs/soccer/walk_and_kick_inputs.yaml").read_text()
    config = config.replace("plugins: [soccer]", "plugins: [soccer, {python: py_kick}]")
    config = config.replace("kick_ball: {type: soccer.KickBall}",
                            "kick_ball: {type: py.KickBall, params: {distance: 0.5, strength: 2}}")
    assert "py.KickBall" in config
    (tmp_path / "soccer.yaml").write_text(config)
    return tmp_path / "soccer.yaml"


def test_a_python_behaviour_replaces_one_of_the_soccer_demos(soccer_with_python_kick):
    manager = arbiter.load(soccer_with_python_kick).manager()
    manager.set_input("robot_pose", [0.0, 0.0, 0.0])
    manager.set_input("ball_visible", True)
    manager.set_input("ball_position", [2.0, 0.0])
    manager.step(3)
    assert not manager.active("kick_ball")
    assert manager.active("go_behind_ball"), "the C++ classes run beside it"
    manager.set_input("ball_position", [0.4, 0.0])   # within the config's distance, 0.5
    manager.step()
    assert manager.active("kick_ball")
    assert not manager.active("go_behind_ball"), "it inhibits the C++ behaviour below it"
    assert manager.actuator("kick") is True


def test_its_params_are_checked_as_a_cpp_classs_are(soccer_with_python_kick):
    config = soccer_with_python_kick.read_text()
    soccer_with_python_kick.write_text(
        config.replace("{distance: 0.5, strength: 2}", "{distance: near}"))
    with pytest.raises(arbiter.ConfigError) as raised:
        arbiter.load(soccer_with_python_kick)
    codes = sorted((d.code, d.line) for d in raised.value.diagnostics)
    line = next(n for n, text in enumerate(config.splitlines(), 1) if "py.KickBall" in text)
    assert ("missing-param", line) in codes, "strength is required"
    assert any(code == "wrong-type" and at == line for code, at in codes)


def test_a_reload_imports_a_module_the_edited_config_newly_names(soccer_with_python_kick, source):
    with_python = soccer_with_python_kick.read_text()
    soccer_with_python_kick.write_text(
        (source / "configs/soccer/walk_and_kick_inputs.yaml").read_text())
    manager = arbiter.load(soccer_with_python_kick).manager()
    manager.set_input("robot_pose", [0.0, 0.0, 0.0])
    manager.set_input("ball_visible", True)
    manager.set_input("ball_position", [2.0, 0.0])
    manager.step(2)
    soccer_with_python_kick.write_text(with_python)
    result = manager.reload()
    assert [change.split(":")[0] for change in result["changes"]] == [
        "~ behaviour control/kick_ball"]
    manager.set_input("ball_position", [0.4, 0.0])   # within the Python class's distance, 0.5
    manager.step()
    assert manager.active("kick_ball")
    assert manager.actuator("kick") is True


def test_an_exception_is_a_fault_with_the_python_traceback(tmp_path):
    (tmp_path / "faulty.py").write_text(FAULTY_MODULE)
    config = tmp_path / "faulty.yaml"
    config.write_text(FAULTY_CONFIG.replace("POLICY", "on_exception: stop"))
    manager = arbiter.load(config).manager()
    manager.step(5)
    assert manager.stopped
    assert manager.steps == 3
    assert "RuntimeError: lost the ball" in manager.stop_reason
    assert "faulty.py(14): execute" in manager.stop_reason, manager.stop_reason
    assert "py.Faulty" in manager.stop_reason


def test_under_the_default_policy_the_run_goes_on(tmp_path):
    (tmp_path / "faulty.py").write_text(FAULTY_MODULE)
    config = tmp_path / "faulty.yaml"
    config.write_text(FAULTY_CONFIG.replace("POLICY", ""))
    manager = arbiter.load(config).manager()
    manager.step(2)
    assert manager.actuator("speed") == pytest.approx((1.0 + 0.5 * 0.2) / 1.5)
    manager.step()
    assert manager.actuator("speed") == 0.2, "the faulty behaviour's write is dropped"
    manager.step()
    assert not manager.stopped
    assert manager.actuator("speed") == pytest.approx((1.0 + 0.5 * 0.2) / 1.5)


def test_a_module_that_does_not_import_is_reported_at_its_name(tmp_path):
    (tmp_path / "broken.py").write_text("import arbiter\nraise ImportError('no numpy here')\n")
    config = tmp_path / "broken.yaml"
    config.write_text("arbiter: 1\nname: b\nplugins: [{python: broken}]\nlayers: []\n")
    with pytest.raises(arbiter.ConfigError) as raised:
        arbiter.load(config)
    first = raised.value.diagnostics[0]
    assert (first.code, first.line, first.column) == ("python-plugin-failed", 3, 20)
    assert first.message == "cannot load Python module 'broken': ImportError: no numpy here"
    assert first.notes == [f"{tmp_path / 'broken.py'}:2: in <module>: raise ImportError('no numpy here')"]


def test_a_bad_port_type_is_reported(tmp_path):
    (tmp_path / "ports.py").write_text(
        "import arbiter\n\nclass P(arbiter.Behaviour):\n    name = 'py.P'\n"
        "    inputs = {'pose': 'vec4'}\n\n    def activation(self, ctx):\n        return 0.0\n")
    config = tmp_path / "ports.yaml"
    config.write_text("arbiter: 1\nname: p\nplugins: [{python: ports}]\nlayers: []\n")
    with pytest.raises(arbiter.ConfigError, match="port 'pose' has type 'vec4'"):
        arbiter.load(config)


def test_outside_python_the_plugin_is_a_located_error(cli, soccer_with_python_kick):
    validate = cli("validate", soccer_with_python_kick)
    assert validate.returncode == 1
    assert "error[python-plugin-unavailable]: plugin 'py_kick' is a Python module" in validate.stderr


def test_a_plugin_entry_that_is_neither_is_a_located_error(tmp_path):
    config = tmp_path / "odd.yaml"
    config.write_text("arbiter: 1\nname: o\nplugins: [{pyhton: x}]\nlayers: []\n")
    with pytest.raises(arbiter.ConfigError,
                       match=r"odd.yaml:3:11: error\[wrong-type\]: expected a plugin name or "
                             r"path, or \{python: MODULE\}"):
        arbiter.load(config)
