"""The Python API: docs/api.md's worked example runs as written and finds the sample's truth;
the public names resolve lazily and carry docstrings."""

from __future__ import annotations

import contextlib
import importlib
import inspect
import io
import json
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_the_worked_example_runs_and_finds_the_samples_missing_physics(monkeypatch):
    """The example of docs/api.md, executed from the repository root: it adopts the effect
    the sample was made with (its truth file) and brings the error to the noise level."""
    text = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    code = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    assert len(code.strip().splitlines()) <= 12
    truth = json.loads((ROOT / "sample_data" / "gl073a_sim.truth.json").read_text())
    monkeypatch.chdir(ROOT)
    out = io.StringIO()
    ns: dict = {}
    with contextlib.redirect_stdout(out):
        exec(compile(code, "docs/api.md", "exec"), ns)
    assert list(ns["diag"].adopted) == list(truth["config"]["effects"])
    assert ns["diag"].augmented.rms_error_pct < 0.1
    assert "adopted sidewall_membrane" in out.getvalue()


def test_public_names_resolve_to_their_modules_objects_with_docstrings():
    import tiremodal_cli as tm

    for name, (module, attr) in tm._API.items():
        obj = getattr(tm, name)
        mod = importlib.import_module(f"tiremodal_cli.{module}")
        assert obj is (mod if attr is None else getattr(mod, attr)), name
        assert (inspect.getdoc(obj) or "").strip(), f"{name} has no docstring"
    assert set(tm.__all__) == {"__version__", *tm._API}


def test_import_is_light():
    """Importing the package loads no numerical library (the command line starts fast)."""
    code = "import sys, tiremodal_cli as tm; print(tm.__version__, 'numpy' in sys.modules, 'scipy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out[1:] == ["False", "False"]
