"""The pytest plugin runs scenario test files as `arbiter test` does and reports their failures
with the same located text."""

import os
import shutil
import subprocess
import sys

import pytest

pytest_plugins = ["pytester"]

FAILING = """\
arbiter_test: 1
config: ../../../configs/paper/walk_and_kick.yaml
steps: 14
expect:
  - {step: 13, active: [go_behind_ball]}
  - {step: 5, activation: {search_for_ball: 0.35}}
"""


@pytest.fixture
def scenarios(tmp_path, source):
    # The paper's configs and scenarios, laid out as in the sources (the scenarios name their
    # configs by relative paths), and nothing else for pytest to collect.
    shutil.copytree(source / "configs/paper", tmp_path / "configs/paper")
    shutil.copytree(source / "tests/scenarios/paper", tmp_path / "tests/scenarios/paper")
    return tmp_path / "tests/scenarios/paper"


def run_pytest(directory, verbosity="-q"):
    return subprocess.run([sys.executable, "-m", "pytest", "-p", "arbiter.pytest_plugin",
                           "-p", "no:cacheprovider", verbosity, str(directory)],
                          capture_output=True, text=True, env=os.environ)


def test_scenario_files_are_collected_and_pass(scenarios):
    run = run_pytest(scenarios, "-v")
    assert run.returncode == 0, run.stdout + run.stderr
    assert "scripted_levels_by_step.test.yaml::scripted_levels_by_step.test.yaml PASSED" in run.stdout
    assert "walk_and_kick_levels.test.json::walk_and_kick_levels.test.json PASSED" in run.stdout


def test_a_failure_is_reported_as_arbiter_test_reports_it(scenarios, cli):
    failing = scenarios / "fails.test.yaml"
    failing.write_text(FAILING)
    run = run_pytest(failing)
    assert run.returncode == 1
    arbiter_test = cli("test", failing)
    assert arbiter_test.returncode == 1
    # `arbiter test`'s lines for the file, from FAIL up to its summary line.
    expected = arbiter_test.stdout.rsplit("\n", 2)[0] + "\n"
    assert expected.startswith("FAIL ")
    assert f"{failing}:5:" in expected, "the failure is at its expectation"
    assert expected in run.stdout
    assert "1 failed" in run.stdout


def test_an_invalid_scenario_fails_with_its_diagnostics(scenarios):
    broken = scenarios / "broken.test.yaml"
    broken.write_text("arbiter_test: 1\nconfig: ../../../configs/paper/walk_and_kick.yaml\n"
                      "stesp: 3\n")
    run = run_pytest(broken)
    assert run.returncode == 1
    assert f"INVALID {broken}" in run.stdout
    assert f"{broken}:3:1: error[" in run.stdout


WAVE_MODULE = '''
import arbiter


class Wave(arbiter.Behaviour):
    """Active from step 3 on."""

    name = "py.Wave"
    outputs = {"speed": "double"}

    def activation(self, ctx):
        return 1.0 if ctx.step >= 3 else 0.0

    def execute(self, ctx):
        ctx.write("speed", 0.5)
'''

WAVE_CONFIG = """\
arbiter: 1
name: wave
plugins: [{python: waving}]
layers:
  - name: control
    actuators:
      speed: {type: double, aggregate: true}
    behaviours:
      wave: {type: py.Wave}
      walk: {type: scripted, params: {activation: 0.5, writes: {speed: 0.2}}}
    inhibitions:
      - wave => walk
"""

WAVE_TEST = """\
arbiter_test: 1
config: wave.yaml
steps: 4
expect:
  - {step: 2, active: [walk], inactive: [wave]}
  - {step: 4, active: [wave], inactive: [walk]}
"""


def test_a_scenario_of_a_config_with_python_classes_runs_them(tmp_path):
    (tmp_path / "waving.py").write_text(WAVE_MODULE)
    (tmp_path / "wave.yaml").write_text(WAVE_CONFIG)
    (tmp_path / "wave.test.yaml").write_text(WAVE_TEST)
    run = run_pytest(tmp_path, "-v")
    assert run.returncode == 0, run.stdout + run.stderr
    assert "wave.test.yaml::wave.test.yaml PASSED" in run.stdout


def test_a_python_module_that_cannot_be_imported_makes_the_scenario_invalid(tmp_path):
    (tmp_path / "waving.py").write_text("import arbiter\nfrom camera import driver\n")
    (tmp_path / "camera.py").write_text("raise ImportError('no camera driver')\n")
    (tmp_path / "wave.yaml").write_text(WAVE_CONFIG)
    (tmp_path / "wave.test.yaml").write_text(WAVE_TEST)
    run = run_pytest(tmp_path)
    assert run.returncode == 1
    assert f"INVALID {tmp_path / 'wave.test.yaml'}" in run.stdout
    config = tmp_path / "wave.yaml"
    assert (f"{config}:3:20: error[python-plugin-failed]: cannot load Python module 'waving': "
            "ImportError: no camera driver\n") in run.stdout
    # The traceback's frames in the user's files, each a note at the module's name.
    assert f"{config}:3:20: note: {tmp_path / 'waving.py'}:2: in <module>: from camera import driver\n" in run.stdout
    assert f"{config}:3:20: note: {tmp_path / 'camera.py'}:1: in <module>:" in run.stdout
    assert "importlib" not in run.stdout
