"""docs/python.md runs as it is shown: its `python` blocks, in order, in one namespace, from the
source tree; what a `print(...)  # text` line says it prints, it prints."""

import contextlib
import io
import os
import re

import pytest


def blocks(text):
    return re.findall(r"```python\n(.*?)```", text, re.S)


def test_the_walk_through_runs_as_shown(source):
    text = (source / "docs/python.md").read_text()
    found = blocks(text)
    assert len(found) >= 5
    namespace = {}
    previous = os.getcwd()
    os.chdir(source)
    try:
        for block in found:
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                exec(compile(block, "docs/python.md", "exec"), namespace)
            printed = out.getvalue()
            for expected in re.findall(r"^\s*print\(.*\)\s+# (.+)$", block, re.M):
                assert expected.strip() in printed, f"{expected!r} not in:\n{printed}"
    finally:
        os.chdir(previous)
