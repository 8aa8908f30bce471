"""Timings of the Python module, for docs/performance.md (it reports; it asserts nothing).

    PYTHONPATH=build/release/python python3 python/bench/bench_python.py build/release/cli/arbiter

1. Stepping a 1000-behaviour graph (10 layers of 100 scripted behaviours, a chaining inhibition
   between neighbours) one step per Python call, against the same manager stepped by one call
   that loops in C++ (Manager.step(count)).
2. A behaviour written in Python (activation + execute writing one output), against the same
   program with a scripted (C++) behaviour in its place: the difference per step is the cost of
   the calls into Python.
3. A 100 000-step trace of the paper's walk-and-kick example read into a DataFrame.
"""

import json
import os
import subprocess
import sys
import tempfile
import time

import arbiter


def graph_config(layers=10, per_layer=100):
    lines = ["arbiter: 1", "name: bench", "layers:"]
    for layer in range(layers):
        lines += [f"  - name: l{layer}", "    actuators:",
                  f"      out{layer}: {{type: double, aggregate: true}}", "    behaviours:"]
        for b in range(per_layer):
            level = (b % 7 + 1) / 8
            lines.append(f"      b{b}: {{type: scripted, params: {{activation: [{level}, 0, 1], "
                         f"writes: {{out{layer}: {b}}}}}}}")
        lines.append("    inhibitions:")
        lines += [f"      - b{b} => b{b + 1}" for b in range(0, per_layer - 1, 2)]
    return "\n".join(lines) + "\n"


def best_of(runs, function):
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return min(times)


def stepping(directory):
    config = os.path.join(directory, "graph.yaml")
    with open(config, "w") as out:
        out.write(graph_config())
    manager = arbiter.load(config).manager()
    steps = 500
    manager.step(100)

    def from_python():
        step = manager.step
        for _ in range(steps):
            step()

    def from_cpp():
        manager.step(steps)

    # Interleaved, the best of many short runs: on a shared machine the other load comes and goes.
    python = cpp = float("inf")
    for _ in range(40):
        python = min(python, best_of(1, from_python) / steps)
        cpp = min(cpp, best_of(1, from_cpp) / steps)
    print(f"step, 1000 behaviours: from Python {python * 1e6:.2f} us, in C++ {cpp * 1e6:.2f} us, "
          f"ratio {python / cpp:.3f}")


PY_BEHAVIOUR = """
import arbiter


class Walk(arbiter.Behaviour):
    name = "bench.Walk"
    outputs = {"speed": "double"}

    def activation(self, ctx):
        return 0.5

    def execute(self, ctx):
        ctx.write("speed", 0.3)
"""

ONE_BEHAVIOUR = """arbiter: 1
name: one
plugins: [{python: bench_walk}]
layers:
  - name: control
    actuators:
      speed: {type: double, aggregate: true}
    behaviours:
      walk: CLASS
"""


def python_behaviour(directory):
    with open(os.path.join(directory, "bench_walk.py"), "w") as out:
        out.write(PY_BEHAVIOUR)
    steps = 20000
    times = {}
    for label, cls in (("python", "bench.Walk"),
                       ("scripted", "{type: scripted, params: {activation: 0.5, "
                                    "writes: {speed: 0.3}}}")):
        config = os.path.join(directory, f"{label}.yaml")
        with open(config, "w") as out:
            out.write(ONE_BEHAVIOUR.replace("CLASS", cls))
        manager = arbiter.load(config).manager()
        manager.step(100)
        times[label] = best_of(10, lambda: manager.step(steps)) / steps
    print(f"step with one Python behaviour {times['python'] * 1e6:.3f} us, with a scripted one "
          f"{times['scripted'] * 1e6:.3f} us: activation + execute in Python "
          f"{(times['python'] - times['scripted']) * 1e6:.3f} us")


def dataframe(directory, cli):
    trace = os.path.join(directory, "run.jsonl")
    subprocess.run([cli, "run", "configs/paper/walk_and_kick.yaml", "--steps", "100000",
                    "--quiet", "--trace", trace], check=True)
    seconds = best_of(3, lambda: arbiter.open_recording(trace).to_dataframe())
    # The same file through Python's own JSON parser, one json.loads per line and nothing else:
    # what the machine's load does to a parse, for comparison.
    def loads():
        with open(trace) as lines:
            for line in lines:
                json.loads(line)

    baseline = best_of(3, loads)
    frame = arbiter.open_recording(trace).to_dataframe()
    size = os.path.getsize(trace) / 1e6
    print(f"to_dataframe, 100 000 steps ({size:.0f} MB trace, {frame.shape[1]} columns): "
          f"{seconds:.2f} s (json.loads of every line: {baseline:.2f} s)")


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as directory:
        stepping(directory)
        python_behaviour(directory)
        if len(sys.argv) > 1:
            dataframe(directory, sys.argv[1])
