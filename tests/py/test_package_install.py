"""The composuite_ros package as a user gets it: built into a wheel and installed without
`-e` (the test venv has it editable, which would hide a module or entry point missing from
the wheel), then imported from that install alone."""

from __future__ import annotations

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "python"


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    # Built by maturin (the package's backend, pinned in the venv; no build isolation: the tests
    # run without network access) from the checkout itself, where python/pyproject.toml finds
    # the native crate (../nodes/python). cargo's dev profile, as the test venv's own install,
    # reuses what `cargo test` built; `pip install ./python` uses release.
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    result = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
         "--disable-pip-version-check", "--config-settings=build-args=--profile dev",
         "-w", str(out), str(PACKAGE)],
        capture_output=True, text=True, env=env, timeout=1200,
    )
    assert result.returncode == 0, result.stderr
    (built,) = out.glob("composuite_ros-*.whl")
    return built


def test_the_wheel_holds_every_module_and_the_eval_entry_point(wheel):
    with zipfile.ZipFile(wheel) as archive:
        names = set(archive.namelist())
        (entry_points,) = [n for n in names if n.endswith(".dist-info/entry_points.txt")]
        entry_text = archive.read(entry_points).decode()
    in_checkout = {f"composuite_ros/{p.name}" for p in (PACKAGE / "composuite_ros").glob("*.py")}
    assert in_checkout, "no modules found in the checkout"
    assert in_checkout <= names, f"missing from the wheel: {sorted(in_checkout - names)}"
    # The native module, as one abi3 library for CPython >= 3.10.
    assert "composuite_ros/_native.abi3.so" in names, sorted(names)
    assert "-cp310-abi3-" in wheel.name, wheel.name
    assert "composuite-eval=composuite_ros.evaluate:main" in entry_text.replace(" ", "")


def test_an_installed_wheel_imports_and_registers_without_the_checkout(wheel, tmp_path):
    target = tmp_path / "site"
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--disable-pip-version-check",
         "--target", str(target), str(wheel)],
        check=True, capture_output=True, text=True,
    )
    # A fresh interpreter with the install first on sys.path (ahead of the venv's editable
    # finder), run from a folder that is not the checkout.
    probe = f"""
import sys
sys.path.insert(0, {str(target)!r})
import importlib, importlib.metadata as md
import gymnasium
import composuite_ros
assert composuite_ros.__file__.startswith({str(target)!r}), composuite_ros.__file__
for name in ("env", "vector", "evaluate", "tasks", "errors", "_link", "_cdr", "episode", "native",
             "_native"):
    module = importlib.import_module("composuite_ros." + name)
    assert module.__file__.startswith({str(target)!r}), module.__file__
spec = gymnasium.spec("composuite_ros/CompoSuite-v0")
assert spec.entry_point == "composuite_ros.env:CompoSuiteRosEnv", spec.entry_point
(dist,) = [d for d in md.distributions(path=[{str(target)!r}]) if d.metadata["Name"] == "composuite_ros"]
(eval_entry,) = [e for e in dist.entry_points if e.name == "composuite-eval"]
assert eval_entry.load() is importlib.import_module("composuite_ros.evaluate").main
print(len(composuite_ros.all_tasks()))
env = gymnasium.make("composuite_ros/CompoSuiteNative-v0")
print(env.reset(seed=3)[1]["seed"], env.step(env.action_space.sample())[4]["step"])
"""
    result = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, capture_output=True,
                            text=True)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["256", "3", "1"]
