# SPDX-License-Identifier: MIT
# The shared bank cache: renders that need the same missing bank at the same time solve it once
# (src/cache/cache_lock.hpp), and the cache holds whole files only afterwards: one bank, and its body's hull.
import subprocess

from conftest import run


def test_concurrent_renders_solve_a_shared_bank_once(repo, cli, tmp_path):
    scene = repo / "examples" / "scenes" / "bar-drop.json"
    cache = tmp_path / "cache"
    renders = [subprocess.Popen([cli, "render", scene, "-o", tmp_path / f"{k}.wav", "--duration", "0.3", "--cache", cache],
                                stderr=subprocess.PIPE, text=True) for k in range(3)]
    summaries = [p.communicate()[1] for p in renders]
    assert all(p.returncode == 0 for p in renders), summaries
    computed = sum(1 for s in summaries if "0 from the cache, 1 computed" in s)
    cached = sum(1 for s in summaries if "1 from the cache, 0 computed" in s)
    assert (computed, cached) == (1, 2), summaries
    assert len({(tmp_path / f"{k}.wav").read_bytes() for k in range(3)}) == 1
    entries = sorted(p.name for p in cache.iterdir())
    banks = [e for e in entries if e.endswith(".modes")]
    assert len(banks) == 1 and all(e.endswith(".hull") for e in entries if e not in banks), entries  # and the bar's hull
    assert run([cli, "info", cache / banks[0]]).returncode == 0
