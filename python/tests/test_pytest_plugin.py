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
