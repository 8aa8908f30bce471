"""Timings of the Python module, for docs/performance.md (it reports; it asserts nothing).

    PYTHONPATH=build/release/python python3 python/bench/bench_python.py build/release/cli/arbiter

1. Stepping a 1000-behaviour graph (10 layers of 100 scripted behaviours, a chaining inhibition
   between neighbours) one step per Python call, against the same manager stepped by one call
   that loops in C++ (Manager.step(count)).
2. A 100 000-step trace of the paper's walk-and-kick example read into a DataFrame.
"""

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
    steps = 5000
    manager.step(100)

    def from_python():
        step = manager.step
        for _ in range(steps):
            step()

    def from_cpp():
        manager.step(steps)

    python = best_of(5, from_python) / steps
    cpp = best_of(5, from_cpp) / steps
    print(f"step, 1000 behaviours: from Python {python * 1e6:.2f} us, in C++ {cpp * 1e6:.2f} us, "
          f"ratio {python / cpp:.3f}")


def dataframe(directory, cli):
    trace = os.path.join(directory, "run.jsonl")
    subprocess.run([cli, "run", "configs/paper/walk_and_kick.yaml", "--steps", "100000",
                    "--quiet", "--trace", trace], check=True)
    seconds = best_of(3, lambda: arbiter.open_recording(trace).to_dataframe())
    frame = arbiter.open_recording(trace).to_dataframe()
    size = os.path.getsize(trace) / 1e6
    print(f"to_dataframe, 100 000 steps ({size:.0f} MB trace, {frame.shape[1]} columns): "
          f"{seconds:.2f} s")


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as directory:
        stepping(directory)
        if len(sys.argv) > 1:
            dataframe(directory, sys.argv[1])
