# SPDX-License-Identifier: MIT
# pytest setup: the strike package and CLI of one build tree (STRIKE_BUILD_DIR, default build/ci),
# as tools/test.sh runs them: PYTHONPATH=build/ci/python /usr/bin/python3 -m pytest python/tests
import os
import pathlib
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
BUILD = pathlib.Path(os.environ.get("STRIKE_BUILD_DIR", REPO / "build" / "ci")).resolve()
sys.path.insert(0, str(BUILD / "python"))


@pytest.fixture(scope="session")
def repo() -> pathlib.Path:
    return REPO


@pytest.fixture(scope="session")
def build_dir() -> pathlib.Path:
    return BUILD


@pytest.fixture(scope="session")
def cli() -> str:
    path = BUILD / "tools" / "strike"
    assert path.is_file(), f"{path}: build the CLI first (cmake --build --preset ci)"
    return str(path)


@pytest.fixture(scope="session")
def cache_dir(tmp_path_factory) -> pathlib.Path:
    """One bank cache for the session, so each test shape is solved once."""
    return tmp_path_factory.mktemp("bank-cache")


def run(args, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run([str(a) for a in args], capture_output=True, text=True, **kwargs)


def wav_float_samples(path) -> "np.ndarray":
    """The float32 samples of a WAV file as the CLI writes it (RIFF, format 3, data chunk),
    read without libsndfile so the test does not trust the writer it checks."""
    import numpy as np
    data = pathlib.Path(path).read_bytes()
    assert data[:4] == b"RIFF" and data[8:12] == b"WAVE", f"{path}: not a RIFF WAVE file"
    pos, fmt = 12, None
    while pos + 8 <= len(data):
        tag, size = data[pos:pos + 4], int.from_bytes(data[pos + 4:pos + 8], "little")
        body = data[pos + 8:pos + 8 + size]
        if tag == b"fmt ":
            fmt = int.from_bytes(body[0:2], "little"), int.from_bytes(body[14:16], "little")
        if tag == b"data":
            assert fmt is not None and fmt[1] == 32 and fmt[0] in (3, 0xFFFE), f"{path}: not 32-bit float: {fmt}"
            return np.frombuffer(body, dtype="<f4")
        pos += 8 + size + (size & 1)
    raise AssertionError(f"{path}: no data chunk")
