"""pytest plugin: every scenario test file (`*.test.yaml`, `*.test.yml`, `*.test.json`) pytest
collects is run as `arbiter test` runs it, each file one test, a failure reported with the text
`arbiter test` prints: every failed expectation at its place (file:line:col), its source line,
and the explanation of what it names.

Turn it on with `pytest -p arbiter.pytest_plugin`, or `pytest_plugins = ["arbiter.pytest_plugin"]`
in a conftest.py. Options: `--arbiter-plugin-path DIR` (repeatable; ARBITER_PLUGIN_PATH is read
too) and `--arbiter-tolerance X` (as `arbiter test --tolerance`)."""

import pytest

from . import _arbiter

_SUFFIXES = (".test.yaml", ".test.yml", ".test.json")


def pytest_addoption(parser):
    group = parser.getgroup("arbiter", "Arbiter scenario tests")
    group.addoption("--arbiter-plugin-path", action="append", default=[], metavar="DIR",
                    help="a directory of Arbiter plugins, as `arbiter test --plugin-path`")
    group.addoption("--arbiter-tolerance", type=float, default=1e-6, metavar="X",
                    help="how far a level may be from the one expected (default 1e-6)")


def pytest_collect_file(parent, file_path):
    if file_path.name.endswith(_SUFFIXES):
        return ScenarioFile.from_parent(parent, path=file_path)
    return None


class ScenarioFile(pytest.File):
    def collect(self):
        yield ScenarioItem.from_parent(self, name=self.path.name)


class ScenarioFailure(Exception):
    """A scenario that failed or could not run; its text is what `arbiter test` prints."""


class ScenarioItem(pytest.Item):
    def runtest(self):
        options = self.config.option
        result = _arbiter._run_scenario(self.path, options.arbiter_plugin_path,
                                        options.arbiter_tolerance)
        self.user_properties.append(("steps", result["steps"]))
        if result["status"] == "failed":
            raise ScenarioFailure(
                f"FAIL {self.path} ({result['failed']} of {result['expectations']} "
                f"expectations failed)\n{result['text']}")
        if result["status"] == "invalid":
            raise ScenarioFailure(f"INVALID {self.path}\n{result['text']}")

    def repr_failure(self, excinfo):
        if isinstance(excinfo.value, ScenarioFailure):
            return str(excinfo.value)
        return super().repr_failure(excinfo)

    def reportinfo(self):
        return self.path, None, f"scenario {self.name}"
