"""State classes written in Python: registered from `plugins: [{python: MODULE}]`, planned in a
state machine's queue beside C++ states, their params per planned instance, their exceptions
put the machine into status 'error' as a C++ state's do."""

import pytest

import arbiter

STATES_MODULE = '''
import arbiter

CALLS = []


class Wait(arbiter.State):
    """Holds for `hold` executions."""

    name = "py.Wait"
    params = {"hold": 1, "label": "wait"}

    def activate(self, ctx):
        CALLS.append(("activate", ctx.param("label"), ctx.cycle))

    def execute(self, ctx):
        done = ctx.executions + 1 >= ctx.param("hold")
        return arbiter.State.PROCEED if done else arbiter.State.HOLD

    def deactivate(self, ctx):
        CALLS.append(("deactivate", ctx.param("label"), ctx.cycle))


class Boom(arbiter.State):
    name = "py.Boom"

    def execute(self, ctx):
        raise RuntimeError("fell over")
'''

CONFIG = """\
arbiter: 1
name: py_states
plugins: [{python: py_states}]
state_machines:
  plan:
    states:
      wait: {type: py.Wait, params: {hold: 2}}
      idle: {type: scripted, params: {hold: 1}}
      boom: {type: py.Boom}
    queue:
      - wait
      - wait: {hold: 3, label: long}
      - idle
      - boom
"""


@pytest.fixture
def config(tmp_path):
    (tmp_path / "py_states.py").write_text(STATES_MODULE)
    (tmp_path / "plan.yaml").write_text(CONFIG)
    return tmp_path / "plan.yaml"


def test_python_states_run_in_the_queue_with_per_instance_params(config):
    manager = arbiter.load(config).manager()
    seen = []
    for _ in range(6):
        manager.step()
        seen.append(manager.state("plan"))
    # hold 2 from the state, then hold 3 from the queue entry, then the C++ scripted state
    assert seen == ["wait", "wait", "wait", "wait", "wait", "idle"]
    import py_states
    # a state that proceeds is left at the start of the next cycle
    assert py_states.CALLS[:4] == [("activate", "wait", 1), ("deactivate", "wait", 3),
                                   ("activate", "long", 3), ("deactivate", "long", 6)]


def test_an_exception_is_a_controller_fault_with_the_traceback(config):
    manager = arbiter.load(config).manager()
    manager.step(8)
    assert manager.status("plan") == "error"
    assert not manager.stopped, "a state's fault stops its machine, not the run"
    error = manager.error("plan")
    assert "controller 'plan'" in error and "state 'boom'" in error, error
    assert "RuntimeError: fell over" in error
    assert "py_states.py(28): execute" in error, error


def test_its_params_are_checked_as_a_cpp_states_are(config):
    config.write_text(CONFIG.replace("{hold: 3, label: long}", "{hold: long}"))
    with pytest.raises(arbiter.ConfigError) as raised:
        arbiter.load(config)
    assert [(d.code, d.line) for d in raised.value.diagnostics
            if d.severity == "error"] == [("wrong-type", 12)], str(raised.value)


def test_execute_must_say_hold_or_proceed(config, tmp_path):
    # Another module name: a module is imported once per process.
    (tmp_path / "py_bool_states.py").write_text(
        STATES_MODULE.replace("return arbiter.State.PROCEED if done else arbiter.State.HOLD",
                              "return done"))
    config.write_text(CONFIG.replace("python: py_states", "python: py_bool_states"))
    manager = arbiter.load(config).manager()
    manager.step()
    assert manager.status("plan") == "error"
    assert "Wait.execute() returned False: it returns State.HOLD or State.PROCEED" in \
        manager.error("plan")
