"""Arbiter, the data-driven behaviour engine, from Python (docs/python.md).

    import arbiter
    program = arbiter.load("configs/paper/walk_and_kick.yaml")
    manager = program.manager()
    manager.step(10)
    manager.levels("kick_ball")   # {'activation': ..., 'requested': ..., 'active': ...}
"""

import os as _os

from ._arbiter import Context, Diagnostic, Manager, Program, Recording, StateContext

__all__ = ["Behaviour", "ConfigError", "Context", "Diagnostic", "Manager", "Program", "Recording", "State",
           "StateContext", "load", "open_recording"]


class ConfigError(Exception):
    """A config that does not load. str() is what `arbiter validate` prints for it (every
    diagnostic with its place, source line and notes, then the counts); `diagnostics` holds them
    as Diagnostic objects (severity, code, file, line, column, message, notes)."""

    def __init__(self, text, diagnostics):
        super().__init__(text)
        self.text = text
        self.diagnostics = list(diagnostics)

    def __str__(self):
        return self.text


class Behaviour:
    """The base of a behaviour class written in Python. A config uses it by `name` once its
    module is listed as `plugins: [{python: MODULE}]` (docs/python.md).

    Declare, as class attributes: `name` ("py.KickBall"); `params`, a dict of param names to a
    default (bool, int, float, str or a list of floats; its type is the param's) or to one of
    those types (a required param); `inputs` and `outputs`, dicts of port names to value types
    ("bool", "int", "double", "string", "vec2", "vec3"), bound as a C++ class's ports are. The
    docstring is the class's description. Params are set as attributes of each instance before
    its first call.

    Callbacks, each given a Context: activation(ctx) (required: the requested level),
    update(ctx), execute(ctx) (ctx.write(port, value), ctx.activation) and inhibited(ctx).
    An exception is a fault of the behaviour, as a C++ exception is (docs/robustness.md)."""

    name = None
    params = {}
    inputs = {}
    outputs = {}

    def activation(self, ctx):
        raise NotImplementedError(f"{type(self).__name__} must define activation(self, ctx)")


class State:
    """The base of a state class written in Python, for a config's `state_machines:`. A config
    uses it by `name` once its module is listed as `plugins: [{python: MODULE}]` (docs/python.md).

    Declare, as class attributes: `name` ("py.Wait"); `params`, as a Behaviour's (a state's
    params may be set per planned instance in the queue: read them with ctx.param(name)). The
    docstring is the class's description.

    Callbacks, each given a StateContext, as a C++ state's: activate(ctx), execute(ctx)
    (required: returns State.HOLD to stay or State.PROCEED to go to the next queued state) and
    deactivate(ctx). An exception puts the state machine into status 'error', as a C++
    state's exception does; Manager.error(machine) holds the message and traceback."""

    HOLD = "hold"
    PROCEED = "proceed"

    name = None
    params = {}

    def execute(self, ctx):
        raise NotImplementedError(f"{type(self).__name__} must define execute(self, ctx)")


def _classes_in(module):
    """The Behaviour and State subclasses with a name that `module` defines, in definition
    order."""
    return [value for value in vars(module).values()
            if isinstance(value, type) and issubclass(value, (Behaviour, State))
            and value not in (Behaviour, State) and value.__module__ == module.__name__
            and value.name]


def _path_argument(function, name, value):
    if isinstance(value, (str, _os.PathLike)):
        return _os.fspath(value)
    raise TypeError(f"{function}(): {name} must be a path (str or os.PathLike), "
                    f"not {type(value).__name__}")


def _paths_argument(function, name, value):
    if isinstance(value, (str, _os.PathLike)):
        value = [value]
    try:
        items = list(value)
    except TypeError:
        raise TypeError(f"{function}(): {name} must be a list of directories, "
                        f"not {type(value).__name__}") from None
    return [_path_argument(function, name, item) for item in items]


def load(path, *, plugin_path=(), strict=False):
    """The program of the config at `path`, or ConfigError carrying every diagnostic.

    `plugin_path` adds plugin directories (as `--plugin-path`; ARBITER_PLUGIN_PATH and the
    default directories are searched too); `strict` makes warnings errors (as `--strict`)."""
    path = _path_argument("load", "path", path)
    plugin_path = _paths_argument("load", "plugin_path", plugin_path)
    if not isinstance(strict, bool):
        raise TypeError(f"load(): strict must be a bool, not {type(strict).__name__}")
    return _arbiter._load(path, plugin_path, strict)


def _manager(self):
    """A new manager running this config (loaded again: the Program stays as it is)."""
    return Manager(self)


def _repr_svg_(self):
    """The graph as SVG for Jupyter, through Graphviz's `dot` when it is installed (None
    otherwise: Jupyter then shows the text)."""
    import shutil
    import subprocess

    dot = shutil.which("dot")
    if dot is None:
        return None
    done = subprocess.run([dot, "-Tsvg"], input=self.to_dot(), capture_output=True, text=True)
    return done.stdout if done.returncode == 0 else None


def _program_repr(self):
    return f"<arbiter.Program {self.name!r} from {self.path!r}>"


def open_recording(path):
    """The trace (`arbiter run --trace`, Manager.trace()) or recording (`--record`, MCAP) at
    `path`, read as `arbiter replay` and `diff` read it. A file that is not one raises
    ValueError with the place and the reason."""
    return Recording(_path_argument("open_recording", "path", path))


def _to_dataframe(self):
    """Every step of the file as a pandas DataFrame: one row per step (indexed by step), a column
    per behaviour level (`layer/name.activation`, `.requested`, `.active`), per actuator
    (`name`, or `name[i]` per component of a vector), per state machine (`name.state`,
    `name.status`), and `t` when the run was timed. A level or value missing at a step (a
    reload added it) is NaN, False or None. The file is read again from its start."""
    import warnings

    import numpy
    import pandas

    names, arrays, truncated = self._columns()
    if truncated:
        warnings.warn(f"{self.path}: {truncated}", stacklevel=2)
    columns = dict(zip(names, arrays))
    steps = columns.pop("step", numpy.zeros(0))
    return pandas.DataFrame(columns, index=pandas.Index(steps.astype(numpy.int64), name="step"))


Recording.to_dataframe = _to_dataframe
Program.manager = _manager
Program._repr_svg_ = _repr_svg_
Program.__repr__ = _program_repr

from . import _arbiter  # noqa: E402  (after the names above: _arbiter raises ConfigError)
