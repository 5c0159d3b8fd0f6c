# SPDX-License-Identifier: MIT
# strike batch: a 20-scene manifest on a 2-worker local Dask cluster, a killed worker, shards.
# Every run is compared byte for byte with a serial run (--shard 1/1, no Dask).
import json
import os
import signal
import subprocess
import sys
import time

import pytest

from conftest import run

SHAPES = [("box:0.2,0.03,0.01", "steel"), ("box:0.15,0.1,0.005", "wood")]
COUNT = 20


@pytest.fixture(scope="module")
def manifest(tmp_path_factory):
    folder = tmp_path_factory.mktemp("batch")
    template = {"sample_rate": 48000, "duration": 0.25, "max_modes": 12, "listener": {"position": [0, -0.5, 0.3]},
                "objects": [{"name": "block", "mesh": "${mesh}", "material": "${material}",
                             "position": [0, 0, "${height}"], "orientation": [0.9998, 0.02, 0, 0]}]}
    (folder / "template.json").write_text(json.dumps(template))
    with open(folder / "scenes.jsonl", "w") as f:
        f.write("# 20 drops of two plates from 20 heights\n")
        for i in range(COUNT):
            mesh, material = SHAPES[i % 2]
            f.write(json.dumps({"id": f"drop{i:02d}", "template": "template.json",
                                "parameters": {"mesh": mesh, "material": material, "height": 0.03 + 0.004 * i}}) + "\n")
    return folder / "scenes.jsonl"


def batch(*args, **kwargs):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    return run([sys.executable, "-m", "strike", "batch", *args], env=env, **kwargs)


def outputs(folder):
    """{name: bytes} of the WAVs, and the names of everything else that is not a finished render."""
    wavs = {p.name: p.read_bytes() for p in folder.glob("*.wav")}
    stray = sorted(p.name for p in folder.iterdir()
                   if not (p.suffix == ".wav" or (p.suffix == ".json" and p.with_suffix(".wav").name in wavs)))
    return wavs, stray


@pytest.fixture(scope="module")
def serial(manifest, tmp_path_factory):
    folder = tmp_path_factory.mktemp("serial")
    r = batch(manifest, "-o", folder, "--shard", "1/1", "--cache", folder.parent / "serial-cache")
    assert r.returncode == 0, r.stderr
    wavs, stray = outputs(folder)
    assert len(wavs) == COUNT and stray == []
    return folder, wavs


def test_serial_run_writes_every_render_with_its_metadata(serial, manifest):
    folder, wavs = serial
    meta = json.loads((folder / "drop07.json").read_text())
    assert meta["parameters"] == {"mesh": SHAPES[1][0], "material": "wood", "height": 0.03 + 0.004 * 7}
    assert meta["scene"]["objects"][0]["position"][2] == 0.03 + 0.004 * 7
    assert meta["line"] == 9 and meta["strike_version"] and meta["seed"] is None
    assert len(meta["banks"][0]["cache_key"]) == 16 and meta["banks"][0]["sounded"]
    assert meta["timings_s"]["total"] > 0 and meta["audio"]["frames"] == 12000
    # Each drop sounds (a silent render would compare equal trivially), and differs from the others.
    assert all(meta["report"]["peak"] > 1e-4 for meta in map(lambda p: json.loads(p.read_text()), folder.glob("*.json")))
    assert len(set(wavs.values())) == COUNT
    # A re-run skips everything and rewrites nothing.
    stamps = {p.name: p.stat().st_mtime_ns for p in folder.iterdir()}
    r = batch(manifest, "-o", folder, "--shard", "1/1", "--cache", folder.parent / "serial-cache")
    assert r.returncode == 0 and "0 rendered, 20 already done" in r.stderr, r.stderr
    assert stamps == {p.name: p.stat().st_mtime_ns for p in folder.iterdir()}


def test_two_worker_local_cluster_renders_the_manifest_solving_each_bank_once(serial, manifest, tmp_path):
    r = batch(manifest, "-o", tmp_path / "out", "--workers", "2", "--cache", tmp_path / "cache")
    assert r.returncode == 0, r.stderr
    assert "renders/s" in r.stderr and "20/20 renders" in r.stderr
    wavs, stray = outputs(tmp_path / "out")
    assert stray == [] and wavs == serial[1]
    metas = [json.loads(p.read_text()) for p in (tmp_path / "out").glob("*.json")]
    assert len({m["worker"]["pid"] for m in metas}) == 2, "both workers rendered"
    assert sum(m["report"]["banks_computed"] for m in metas) == len(SHAPES)
    # The banks, one per shape (beside them each body's convex hull, .hull).
    assert sorted(p.name for p in (tmp_path / "cache").glob("*.modes")) == sorted(
        {m["banks"][0]["cache_key"] + ".modes" for m in metas})
    assert all(p.suffix in (".modes", ".hull") for p in (tmp_path / "cache").iterdir())


def test_a_killed_worker_loses_nothing_and_a_rerun_completes_the_set(serial, manifest, tmp_path):
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    proc = subprocess.Popen([sys.executable, "-m", "strike", "batch", manifest, "-o", out, "--workers", "2", "--cache",
                             tmp_path / "cache"], env=env, stderr=subprocess.PIPE, text=True)
    victim = None
    deadline = time.monotonic() + 120
    while victim is None and time.monotonic() < deadline and proc.poll() is None:
        done = list(out.glob("*.json")) if out.exists() else []
        if len(done) >= 3:
            victim = json.loads(done[0].read_text())["worker"]["pid"]
        time.sleep(0.01)
    assert victim is not None, "the batch ended before a worker could be killed"
    os.kill(victim, signal.SIGKILL)
    proc.communicate(timeout=300)
    finished = len(list(out.glob("*.json")))
    r = batch(manifest, "-o", out, "--workers", "2", "--cache", tmp_path / "cache")
    assert r.returncode == 0, r.stderr
    assert f"{COUNT - finished} rendered, {finished} already done" in r.stderr, r.stderr
    wavs, stray = outputs(out)
    assert stray == [], "partial or temporary files left behind"
    assert wavs == serial[1]


def test_two_shards_plus_the_rest_equal_the_whole(serial, manifest, cli, tmp_path):
    out = tmp_path / "out"
    r = batch(manifest, "-o", out, "--shard", "1/3", "--cache", tmp_path / "cache")
    assert r.returncode == 0, r.stderr
    # `strike batch` is the same program (the CLI execs python3 -m strike.batch).
    r = run([cli, "batch", manifest, "-o", out, "--shard", "2/3", "--cache", tmp_path / "cache"])
    assert r.returncode == 0, r.stderr
    assert len(list(out.glob("*.wav"))) == 7 + 7  # lines 1, 4, 7, ... and 2, 5, 8, ... of 20
    r = batch(manifest, "-o", out, "--shard", "1/1", "--cache", tmp_path / "cache")
    assert r.returncode == 0 and "6 rendered, 14 already done" in r.stderr, r.stderr
    wavs, stray = outputs(out)
    assert stray == [] and wavs == serial[1]


def test_bad_manifest_lines_name_the_line_key_and_value(manifest, tmp_path):
    bad = tmp_path / "bad.jsonl"
    lines = manifest.read_text().splitlines()
    lines[3] = lines[3].replace('"parameters"', '"colour": "red", "parameters"')
    bad.write_text("\n".join(lines))
    (tmp_path / "template.json").write_text((manifest.parent / "template.json").read_text())
    r = batch(bad, "-o", tmp_path / "out")
    assert r.returncode == 1 and f"{bad}:4: error: unknown key 'colour'" in r.stderr, r.stderr
    lines = manifest.read_text().splitlines()
    lines[2] = lines[2].replace('"height"', '"hieght"')
    bad.write_text("\n".join(lines))
    r = batch(bad, "-o", tmp_path / "out")
    assert r.returncode == 1 and "bad.jsonl:3: error:" in r.stderr and "${height}" in r.stderr, r.stderr
    # A scene error surfaces from the render with the engine's message and fails the batch.
    lines = manifest.read_text().splitlines()
    lines[1] = lines[1].replace('"steel"', '"unobtainium"')
    bad.write_text("\n".join(lines[:3]))
    r = batch(bad, "-o", tmp_path / "out", "--shard", "1/1", "--cache", tmp_path / "cache")
    assert r.returncode == 1 and "id drop00" in r.stderr and "unknown material 'unobtainium'" in r.stderr, r.stderr
    assert not (tmp_path / "out" / "drop00.wav").exists() and (tmp_path / "out" / "drop01.wav").exists()


def test_output_per_line_renders_binaural_and_ambisonics_as_the_cli(serial, manifest, cli, tmp_path):
    # A line's "output" is `strike render --output`: the same samples as the CLI's render of its scene.
    import numpy as np
    from conftest import wav_float_samples
    lines = [json.loads(line) for line in manifest.read_text().splitlines()[1:3]]
    lines[0]["output"], lines[1]["output"] = "binaural", "ambix1"
    (tmp_path / "template.json").write_text((manifest.parent / "template.json").read_text())
    (tmp_path / "two.jsonl").write_text("\n".join(json.dumps(line) for line in lines))
    cache = serial[0].parent / "serial-cache"
    r = batch(tmp_path / "two.jsonl", "-o", tmp_path / "out", "--shard", "1/1", "--cache", cache)
    assert r.returncode == 0, r.stderr
    for line, channels in zip(lines, (2, 4)):
        meta = json.loads((tmp_path / "out" / (line["id"] + ".json")).read_text())
        assert meta["audio"]["output"] == line["output"] and meta["audio"]["channels"] == channels
        (tmp_path / "scene.json").write_text(json.dumps(meta["scene"]))
        wav = tmp_path / "cli.wav"
        r = run([cli, "render", tmp_path / "scene.json", "-o", wav, "--cache", cache, "--output", line["output"], "--quiet"])
        assert r.returncode == 0, r.stderr
        batch_samples = wav_float_samples(tmp_path / "out" / (line["id"] + ".wav"))
        assert np.abs(batch_samples).max() > 1e-4
        assert np.array_equal(batch_samples.view(np.uint32), wav_float_samples(wav).view(np.uint32))
    # A bad output, and an hrtf without binaural, name the line, key and value.
    lines[1]["output"] = "octo"
    (tmp_path / "bad.jsonl").write_text("\n".join(json.dumps(line) for line in lines))
    r = batch(tmp_path / "bad.jsonl", "-o", tmp_path / "bad")
    assert r.returncode == 1 and 'bad.jsonl:2: error: output = "octo"' in r.stderr, r.stderr
    lines[1]["output"], lines[1]["hrtf"] = "stereo", "head.sofa"
    (tmp_path / "bad.jsonl").write_text("\n".join(json.dumps(line) for line in lines))
    r = batch(tmp_path / "bad.jsonl", "-o", tmp_path / "bad")
    assert r.returncode == 1 and 'bad.jsonl:2: error: hrtf = "head.sofa" goes with' in r.stderr, r.stderr
