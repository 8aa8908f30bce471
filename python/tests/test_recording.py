"""open_recording(): traces and MCAP recordings read step by step and as a DataFrame."""

import math

import numpy
import pytest

import arbiter


@pytest.fixture
def trace(tmp_path, source):
    """A 20-step trace of the paper's walk-and-kick example, written by a Python manager, and
    the levels and actuators the manager had at each step."""
    manager = arbiter.load(source / "configs/paper/walk_and_kick.yaml").manager()
    manager.trace(tmp_path / "run.jsonl")
    seen = []
    for _ in range(20):
        manager.step()
        seen.append((manager.all_levels(), manager.actuators()))
    manager.finish()
    return tmp_path / "run.jsonl", seen


def test_a_trace_reads_step_by_step(trace):
    path, seen = trace
    recording = arbiter.open_recording(path)
    assert recording.header["name"] == "walk_and_kick"
    records = list(recording)
    assert [record["step"] for record in records] == list(range(1, 21))
    assert records[12]["layers"]["control"]["kick_ball"]["active"] is True


def test_the_dataframe_has_a_row_per_step_and_a_column_per_level_and_component(trace):
    path, seen = trace
    frame = arbiter.open_recording(path).to_dataframe()
    assert list(frame.index) == list(range(1, 21))
    assert frame.index.name == "step"
    # In the trace's order: each layer's behaviours in execution order.
    assert list(frame.columns[:3]) == ["control/kick_ball.requested",
                                       "control/kick_ball.activation", "control/kick_ball.active"]
    assert frame["control/kick_ball.active"].dtype == bool
    for step, (levels, actuators) in enumerate(seen, start=1):
        row = frame.loc[step]
        for behaviour, level in levels.items():
            assert row[f"{behaviour}.activation"] == level["activation"]
            assert row[f"{behaviour}.requested"] == level["requested"]
            assert row[f"{behaviour}.active"] == level["active"]
        assert tuple(row[f"gait_velocity[{i}]"] for i in range(3)) == actuators["gait_velocity"]
        assert row["head_angle"] == actuators["head_angle"]
        assert row["kick"] == actuators["kick"]


def test_columns_are_numpy_arrays(trace):
    path, _ = trace
    frame = arbiter.open_recording(path).to_dataframe()
    assert isinstance(frame["control/go_behind_ball.activation"].to_numpy(), numpy.ndarray)
    assert frame["control/go_behind_ball.activation"].dtype == numpy.float64


def test_an_mcap_recording_reads_as_its_trace_does(cli, tmp_path):
    cli("run", "configs/paper/goalie_plan.yaml", "--steps", "12", "--quiet",
        "--trace", tmp_path / "run.jsonl", "--record", tmp_path / "run.mcap")
    from_trace = arbiter.open_recording(tmp_path / "run.jsonl").to_dataframe()
    from_mcap = arbiter.open_recording(tmp_path / "run.mcap").to_dataframe()
    assert list(from_mcap["goalie.state"])[:6] == ["wait_for_button"] * 5 + ["walk_to_pose"]
    assert (from_trace["goalie.state"] == from_mcap["goalie.state"]).all()
    assert [r["step"] for r in arbiter.open_recording(tmp_path / "run.mcap")] == list(range(1, 13))


def test_a_level_missing_before_a_reload_is_nan(tmp_path):
    config = tmp_path / "grow.yaml"
    config.write_text("arbiter: 1\nname: grow\nlayers:\n  - name: l\n    behaviours:\n"
                      "      a: {type: scripted, params: {activation: 1}}\n")
    manager = arbiter.load(config).manager()
    manager.trace(tmp_path / "run.jsonl")
    manager.step()
    config.write_text(config.read_text() + "      b: {type: scripted, params: {activation: 0.5}}\n")
    manager.reload()
    manager.step()
    manager.finish()
    frame = arbiter.open_recording(tmp_path / "run.jsonl").to_dataframe()
    assert math.isnan(frame.loc[1, "l/b.activation"])
    assert frame.loc[2, "l/b.activation"] == 0.5


def test_columns_follow_their_names_when_a_reload_reorders_the_record(tmp_path):
    config = tmp_path / "order.yaml"
    a = "      a: {type: scripted, params: {activation: 1}}\n"
    b = "      b: {type: scripted, params: {activation: 0.5}}\n"
    head = "arbiter: 1\nname: order\nlayers:\n  - name: l\n    behaviours:\n"
    config.write_text(head + a + b)
    manager = arbiter.load(config).manager()
    manager.trace(tmp_path / "run.jsonl")
    manager.step(2)
    config.write_text(head + b + a)  # b now executes, and is written, first
    manager.reload()
    manager.step(2)
    manager.finish()
    frame = arbiter.open_recording(tmp_path / "run.jsonl").to_dataframe()
    assert list(frame["l/a.activation"]) == [1, 1, 1, 1]
    assert list(frame["l/b.activation"]) == [0.5, 0.5, 0.5, 0.5]


def test_a_file_that_is_no_trace_is_a_located_error(tmp_path):
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"arbiter_trace": 1, "name": "x", "layers": []}\n{"step": "one"}\n')
    with pytest.raises(ValueError, match=r"bad.jsonl:2:\d+: error"):
        list(arbiter.open_recording(bad))
    with pytest.raises(ValueError, match=r"bad.jsonl:2:\d+: error"):
        arbiter.open_recording(bad).to_dataframe()
    with pytest.raises(ValueError, match="cannot"):
        arbiter.open_recording(tmp_path / "missing.jsonl")
    with pytest.raises(TypeError, match=r"open_recording\(\): path must be"):
        arbiter.open_recording(None)


def test_a_program_renders_as_svg_when_graphviz_is_installed(source):
    import shutil

    program = arbiter.load(source / "configs/paper/walk_and_kick.yaml")
    svg = program._repr_svg_()
    if shutil.which("dot"):
        assert "<svg" in svg
    else:
        assert svg is None
