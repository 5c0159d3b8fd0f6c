# SPDX-License-Identifier: MIT
# Installing and importing the package as a Python user does (docs/install.md).
import os
import pathlib
import subprocess
import sys

import pytest

import strike
from conftest import run


def test_pip_installs_into_a_venv_of_debians_packages(repo, build_dir, tmp_path):
    # `python3 -m venv --system-site-packages` + `pip install --no-build-isolation ./python`, offline
    # (--no-index): the build drives CMake; STRIKE_CMAKE_BUILD_DIR reuses this build tree, so only
    # strike_python is brought up to date.
    venv = tmp_path / "venv"
    r = run([sys.executable, "-m", "venv", "--system-site-packages", venv])
    assert r.returncode == 0, r.stderr
    python = venv / "bin" / "python"
    env = dict(os.environ, STRIKE_CMAKE_BUILD_DIR=str(build_dir), PIP_DISABLE_PIP_VERSION_CHECK="1")
    env.pop("PYTHONPATH", None)
    r = run([python, "-m", "pip", "install", "--no-build-isolation", "--no-index", repo / "python"], env=env)
    assert r.returncode == 0, r.stdout + r.stderr
    assert not (repo / "python" / "build").exists() and not list((repo / "python").glob("*.egg-info"))
    code = ("import strike; b = strike.modes('box:0.1,0.01,0.01', material='steel', max_modes=3, "
            "error_estimate=False); print(strike.__file__); print(b.mode_count); print(strike.__version__)")
    r = run([python, "-c", code], cwd=tmp_path, env=env)
    assert r.returncode == 0, r.stderr
    where, count, version = r.stdout.split()
    assert pathlib.Path(where).resolve().is_relative_to(venv.resolve())
    assert count == "3"
    assert version == strike.__version__
    assert (venv / "bin" / "strike-batch").read_text().startswith(f"#!{python}")


def test_a_python_without_numpy_says_how_to_fix_it(build_dir, tmp_path):
    # python3 -S: no site-packages, so no numpy, as with another python3 first on PATH.
    code = f"import sys; sys.path.insert(0, {str(build_dir / 'python')!r}); import strike"
    r = run([sys.executable, "-S", "-c", code], cwd=tmp_path)
    assert r.returncode != 0
    assert "strike needs numpy" in r.stderr, r.stderr
    assert "python3-numpy" in r.stderr and "--system-site-packages" in r.stderr, r.stderr


def test_dir_shows_what_the_package_offers():
    names = dir(strike)
    for imported in ("np", "os", "json", "Any", "Mapping"):
        assert imported not in names
    for offered in ("render", "modes", "hit", "Bank", "InputError", "__version__"):
        assert offered in names


def test_scene_dict_errors_name_the_dict_not_a_path(tmp_path):
    scene = {"sample_rate": 48000, "duration": 1, "objects": [{"name": "a", "mesh": "box:0.1,0.1,0.1",
                                                               "material": "steell"}]}
    with pytest.raises(strike.InputError) as caught:
        strike.render(scene, cache=False)
    message = str(caught.value)
    assert message.startswith("scene dict: error: objects[0].material: unknown material 'steell'"), message
    assert os.getcwd() not in message
    with pytest.raises(strike.InputError) as caught:
        strike.render(scene, cache=False, base_dir=tmp_path)
    assert str(caught.value).startswith(f"scene dict (paths from {tmp_path}): error: objects[0].material"), caught.value
