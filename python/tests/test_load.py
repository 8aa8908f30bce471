"""arbiter.load(): a program, or ConfigError carrying every diagnostic as `arbiter validate`
reports them."""

import pathlib

import pytest

import arbiter


def test_a_valid_config_loads_as_its_program(source):
    program = arbiter.load(source / "configs/paper/walk_and_kick.yaml")
    assert program.name == "walk_and_kick"
    assert program.layers == ["control"]
    assert program.behaviours == ["control/kick_ball", "control/go_behind_ball",
                                  "control/search_for_ball", "control/head_control"]
    assert program.actuators == ["gait_velocity", "head_angle", "kick"]
    assert program.rate_hz == 15


def test_a_config_error_carries_every_diagnostic_with_its_place():
    with pytest.raises(arbiter.ConfigError) as raised:
        arbiter.load("tests/data/invalid/bad_key.yaml")
    diagnostics = raised.value.diagnostics
    assert [(d.severity, d.code, d.file, d.line, d.column) for d in diagnostics] == [
        ("error", "bad-key", "tests/data/invalid/bad_key.yaml", 6, 7),
        ("error", "bad-key", "tests/data/invalid/bad_key.yaml", 7, 9),
    ]
    assert diagnostics[1].message == "a mapping key must be a name, found a list of 2 items"


@pytest.mark.parametrize("config", ["tests/data/invalid/bad_key.yaml",
                                    "tests/data/invalid/cross_layer_inhibition.yaml",
                                    "tests/data/invalid/unknown_class.yaml"])
def test_a_config_errors_text_is_what_arbiter_validate_prints(cli, config):
    with pytest.raises(arbiter.ConfigError) as raised:
        arbiter.load(config)
    validate = cli("validate", config)
    assert validate.returncode == 1
    assert str(raised.value) == validate.stderr
    assert "".join(str(d) for d in raised.value.diagnostics) in validate.stderr


def test_notes_come_with_their_diagnostic():
    with pytest.raises(arbiter.ConfigError) as raised:
        arbiter.load("tests/data/invalid/unknown_class.yaml")
    notes = [note for d in raised.value.diagnostics for note in d.notes]
    assert notes, "an unknown class is reported with the known ones"
    assert any("known" in note or "did you mean" in note for note in notes)


def test_a_missing_file_is_a_config_error_not_a_crash(tmp_path):
    with pytest.raises(arbiter.ConfigError) as raised:
        arbiter.load(tmp_path / "nothing.yaml")
    assert raised.value.diagnostics[0].file == str(tmp_path / "nothing.yaml")


def test_strict_makes_warnings_errors(source, tmp_path):
    config = tmp_path / "duplicate.yaml"
    config.write_text((source / "configs/paper/walk_and_kick.yaml").read_text().replace(
        "  - kick_ball => go_behind_ball\n",
        "  - kick_ball => go_behind_ball\n      - kick_ball => go_behind_ball\n"))
    program = arbiter.load(config)
    assert [d.severity for d in program.warnings] == ["warning"]
    with pytest.raises(arbiter.ConfigError):
        arbiter.load(config, strict=True)


@pytest.mark.parametrize("call, parameter", [
    (lambda: arbiter.load(5), "path"),
    (lambda: arbiter.load("x.yaml", plugin_path=[3]), "plugin_path"),
    (lambda: arbiter.load("x.yaml", strict="yes"), "strict"),
])
def test_a_wrong_argument_type_is_a_type_error_naming_the_parameter(call, parameter):
    with pytest.raises(TypeError, match=rf"load\(\): {parameter} must be"):
        call()


def test_pathlib_paths_are_accepted(source):
    assert arbiter.load(pathlib.Path(source) / "configs/paper/walk_and_kick.yaml").name


def test_the_graph_is_the_dump_commands(cli, source):
    program = arbiter.load("configs/paper/walk_and_kick.yaml")
    assert program.to_dot() == cli("dump", "configs/paper/walk_and_kick.yaml", "--format",
                                   "dot").stdout
    assert program.dump() == cli("dump", "configs/paper/walk_and_kick.yaml").stdout
