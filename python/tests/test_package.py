# SPDX-License-Identifier: MIT
# The strike package against the CLI: same samples, same bytes, same error messages.
import json
import os
import pathlib
import subprocess
import sys
import threading

import numpy as np
import pytest

import strike
from conftest import run, wav_float_samples

BAR = "box:0.3,0.02,0.02"  # examples/scenes/bar-drop.json's bar


def test_imports_from_a_fresh_install(build_dir, tmp_path):
    # `cmake --install --component python --prefix P` (docs/install.md) and nothing else on the path.
    r = run(["cmake", "--install", build_dir, "--component", "python", "--prefix", tmp_path])
    assert r.returncode == 0, r.stderr
    site = tmp_path / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" / "site-packages"
    for name in ("__init__.py", "_strike.pyi", "py.typed", "batch.py"):
        assert (site / "strike" / name).is_file(), name
    assert (tmp_path / "bin" / "strike-batch").is_file()
    code = ("import strike, sys; b = strike.modes('box:0.1,0.01,0.01', material='steel', max_modes=3, "
            "error_estimate=False); print(strike.__file__); print(b.mode_count)")
    env = {"PATH": os.environ.get("PATH", ""), "PYTHONPATH": str(site), "HOME": str(tmp_path)}
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    where, count = r.stdout.split()
    assert pathlib.Path(where).resolve().is_relative_to(site.resolve())
    assert count == "3"


def test_render_equals_the_cli_byte_for_byte(repo, cli, cache_dir, tmp_path):
    scene = repo / "examples" / "scenes" / "bar-drop.json"
    wav = tmp_path / "cli.wav"
    csv = tmp_path / "cli-events.csv"
    r = run([cli, "render", scene, "-o", wav, "--duration", "0.5", "--cache", cache_dir, "--events", csv, "--quiet"])
    assert r.returncode == 0, r.stderr
    result = strike.render(scene, duration=0.5, cache=cache_dir)
    assert result.rate == 48000 and result.audio.dtype == np.float32 and result.audio.shape == (24000,)
    cli_samples = wav_float_samples(wav)
    # Bit patterns, not values: -0.0 == 0.0 and NaN != NaN would hide differences.
    assert np.array_equal(result.audio.view(np.uint32), cli_samples.view(np.uint32))
    assert np.abs(result.audio).max() > 1e-3, "silence would match trivially"
    result.save(tmp_path / "py.wav")
    assert (tmp_path / "py.wav").read_bytes() == wav.read_bytes()
    # A scene given as a dict renders the same.
    as_dict = json.loads(scene.read_text())
    again = strike.render(as_dict, duration=0.5, cache=cache_dir)
    assert np.array_equal(again.audio.view(np.uint32), cli_samples.view(np.uint32))
    assert again.metadata["scene"] == as_dict
    # Events: the first impact is the bar landing at about sqrt(2 h / g) (h: 0.15 m less half the bar's 0.02 m).
    impacts = result.events[result.events["new_contact"]]
    assert impacts[0]["time_s"] == pytest.approx(np.sqrt(2 * 0.14 / 9.81), abs=2e-3)
    assert result.metadata["events"] == len(result.events) and result.metadata["bodies"] == ["bar"]
    result.save_events_csv(tmp_path / "py-events.csv")
    assert (tmp_path / "py-events.csv").read_bytes() == csv.read_bytes()
    rows = [line.split(",") for line in csv.read_text().splitlines()[1:]]
    assert len(rows) == len(result.events) > 100
    np.testing.assert_allclose(result.events["time_s"], [float(row[0]) for row in rows], rtol=1e-8)
    np.testing.assert_allclose(result.events["point_world"][:, 2], [float(row[9]) for row in rows], rtol=1e-8, atol=1e-12)
    assert all((e["body_b"] == -1) == (row[2] == "ground") for e, row in zip(result.events, rows))
    # The contact state columns come after step_time_s (docs/contact.md), in the same order.
    header = csv.read_text().splitlines()[0].split(",")
    assert header.index("step_time_s") == 19 and header[20:] == [
        "normal_force_n", "slip_x_m_s", "slip_y_m_s", "slip_z_m_s", "rolling_speed_m_s",
        "track_speed_a_m_s", "track_speed_b_m_s", "patch_radius_m", "motion"]
    np.testing.assert_allclose(result.events["normal_force_n"], [float(row[20]) for row in rows], rtol=1e-8)
    np.testing.assert_allclose(result.events["slip_velocity_m_s"][:, 0], [float(row[21]) for row in rows], rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(result.events["patch_radius_m"], [float(row[27]) for row in rows], rtol=1e-8)
    assert list(result.events["motion"]) == [row[28] for row in rows]
    # 1 ms steps: the normal force is the normal impulse over the step.
    np.testing.assert_allclose(result.events["normal_force_n"], result.events["normal_impulse_n_s"] / 1e-3, rtol=1e-12)


def test_default_bank_and_tap_equal_the_clis(cli, tmp_path):
    """With no order, Python's bank is the CLI's (the library's automatic order: Tet10 for this thin
    bar, where Tet4 rang 8% sharp; steel named, as the CLI has no default material), and
    strike.hit()'s default tap is `strike hit`'s."""
    bank_path = tmp_path / "default.modes"
    r = run([cli, "modes", BAR, "--material", "steel", "--max-modes", "4", "--size", "0.005", "--no-error-estimate",
             "--no-transfer", "-o", bank_path])
    assert r.returncode == 0, r.stderr
    assert "Tet10 chosen" in r.stderr
    bank = strike.modes(BAR, max_modes=4, size=0.005, error_estimate=False, transfer=False)
    cli_bank = strike.Bank.load(bank_path)
    assert bank.element_order == cli_bank.element_order == 2
    assert np.array_equal(bank.eigenvalues, cli_bank.eigenvalues)
    wav = tmp_path / "tap.wav"
    r = run([cli, "hit", bank_path, "-o", wav, "--duration", "0.2", "--quiet"])
    assert r.returncode == 0, r.stderr
    audio = strike.hit(cli_bank, duration=0.2)
    assert np.array_equal(audio.view(np.uint32), wav_float_samples(wav).view(np.uint32))


def test_output_formats_equal_the_cli_and_turn_with_the_listener(repo, cli, cache_dir, tmp_path):
    # `output` is `strike render --output`; the listener's orientation comes with the scene.
    scene = json.loads((repo / "examples" / "scenes" / "bar-drop.json").read_text())
    scene["listener"]["look_at"] = [0.0, 0.0, 0.0]
    (tmp_path / "scene.json").write_text(json.dumps(scene))
    wav = tmp_path / "cli.wav"
    r = run([cli, "render", tmp_path / "scene.json", "-o", wav, "--duration", "0.4", "--cache", cache_dir,
             "--output", "ambix1", "--quiet"])
    assert r.returncode == 0, r.stderr
    result = strike.render(scene, duration=0.4, cache=cache_dir, output="ambix1")
    assert result.audio.shape == (19200, 4)
    assert np.array_equal(result.audio.reshape(-1).view(np.uint32), wav_float_samples(wav).view(np.uint32))
    # The omni channel is the mono render to -100 dB re peak, modes falling asleep under the
    # audibility threshold included (both paths' modes sleep when their sum does, as in mono:
    # docs/listener.md; -143.6 dB measured on the bar drop).
    mono = strike.render(scene, duration=0.4, cache=cache_dir)
    difference = result.audio[:, 0].astype(np.float64) - mono.audio
    assert np.abs(mono.audio).max() > 1e-2
    assert np.abs(difference).max() < 1e-5 * np.abs(mono.audio).max()
    with pytest.raises(strike.InputError, match="output = 'octo'"):
        strike.render(scene, duration=0.4, cache=cache_dir, output="octo")
    # Binaural (the KEMAR set by default, read by the package as by the CLI): the CLI's samples.
    wav = tmp_path / "binaural.wav"
    r = run([cli, "render", tmp_path / "scene.json", "-o", wav, "--duration", "0.4", "--cache", cache_dir,
             "--output", "binaural", "--quiet"])
    assert r.returncode == 0, r.stderr
    binaural = strike.render(scene, duration=0.4, cache=cache_dir, output="binaural")
    assert binaural.audio.shape == (19200, 2)
    assert np.array_equal(binaural.audio.reshape(-1).view(np.uint32), wav_float_samples(wav).view(np.uint32))
    with pytest.raises(strike.InputError, match="missing.sofa"):
        strike.render(scene, duration=0.4, cache=cache_dir, output="binaural", hrtf=tmp_path / "missing.sofa")


def test_modes_and_hit_equal_the_cli(cli, tmp_path):
    bank_path = tmp_path / "cli.modes"
    r = run([cli, "modes", BAR, "--material", "steel", "--order", "2", "--max-modes", "8", "--no-error-estimate", "-o", bank_path, "--quiet"])
    assert r.returncode == 0, r.stderr
    bank = strike.modes(BAR, material="steel", order=2, max_modes=8, error_estimate=False)
    cli_bank = strike.Bank.load(bank_path)
    assert np.array_equal(bank.eigenvalues, cli_bank.eigenvalues)
    assert bank.mode_count == 8
    # Free-free Euler-Bernoulli bar, first bending mode: f = (4.730^2 / 2 pi) sqrt(E I / rho A) / L^2.
    m = strike.material("steel")
    f1 = 4.7300407 ** 2 / (2 * np.pi) * np.sqrt(m["youngs_pa"] * 0.02 ** 2 / 12 / m["density_kg_m3"]) / 0.3 ** 2
    # Shear and rotary inertia (Timoshenko) lower it by about 1 % at this slenderness.
    assert bank.frequencies_hz[0] == pytest.approx(f1, rel=0.03)
    assert np.all(bank.decay_per_s > 0)
    wav = tmp_path / "hit.wav"
    r = run([cli, "hit", bank_path, "-o", wav, "--at", "0.15,0,0.01", "--impulse", "0,0,-0.01", "--duration", "0.5", "--quiet"])
    assert r.returncode == 0, r.stderr
    audio = strike.hit(cli_bank, at=(0.15, 0, 0.01), impulse=(0, 0, -0.01), duration=0.5)
    assert audio.dtype == np.float32 and audio.shape == (24000,)
    assert np.array_equal(audio.view(np.uint32), wav_float_samples(wav).view(np.uint32))
    assert np.abs(audio).max() > 1e-4
    bank.save(tmp_path / "py.modes")
    assert np.array_equal(strike.Bank.load(tmp_path / "py.modes").frequencies_hz, bank.frequencies_hz)


def test_errors_name_the_key_and_value_as_the_cli_does(repo, cli, tmp_path):
    scene = json.loads((repo / "examples" / "scenes" / "bar-drop.json").read_text())
    scene["objects"][0]["velocity"] = [0, "fast", 0]
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(scene))
    r = run([cli, "render", path, "-o", tmp_path / "out.wav", "--quiet"])
    assert r.returncode == 1
    with pytest.raises(strike.InputError) as raised:
        strike.render(path, cache=None)
    assert r.stderr.strip() == f"strike render: {raised.value}"
    assert "objects[0].velocity[1]" in str(raised.value) and "fast" in str(raised.value)
    assert not (tmp_path / "out.wav").exists()
    scene["objects"][0]["velocity"] = [0, 0, 0]
    scene["objects"][0]["colour"] = "red"
    with pytest.raises(ValueError, match=r"objects\[0\].*colour"):
        strike.render(scene, cache=None)
    with pytest.raises(strike.InputError, match=r"nothing\.json"):
        strike.render(tmp_path / "nothing.json")
    with pytest.raises(strike.InputError, match=r"order = 3 \(must be 1 or 2\)"):
        strike.modes(BAR, order=3)
    with pytest.raises(strike.InputError, match=r"unknown material 'unobtainium'"):
        strike.modes(BAR, material="unobtainium")
    with pytest.raises(strike.InputError, match=r"material.poisson = 0.7"):
        strike.modes(BAR, material={"youngs_pa": 1e9, "poisson": 0.7, "density_kg_m3": 1000})
    bank = strike.modes("box:0.1,0.01,0.01", max_modes=2, error_estimate=False)
    with pytest.raises(strike.InputError, match=r"rate = 100 \(must be 8000 to 384000 Hz\)"):
        strike.hit(bank, rate=100)
    with pytest.raises(strike.InputError, match=r"vertex = 100000 \(the bank has surface vertices 0 to"):
        strike.hit(bank, vertex=100000)


def test_the_gil_is_released_while_rendering():
    bank = strike.modes("box:0.1,0.01,0.01", max_modes=20, error_estimate=False)
    count = [0]
    stop = threading.Event()

    def spin():
        while not stop.is_set():
            count[0] += 1

    thread = threading.Thread(target=spin)
    thread.start()
    try:
        before = count[0]
        strike.hit(bank, duration=120, rate=48000)  # several hundred ms of synthesis
        during = count[0] - before
    finally:
        stop.set()
        thread.join()
    # Holding the GIL, the spinning thread would get at most a switch interval (5 ms) or two.
    assert during > 100000, during


def test_a_session_changes_no_byte_and_stays_under_its_cap(repo, cli, cache_dir, tmp_path):
    # The CLI's bytes (no session), then the same scene through a cold and a warm strike.Session.
    scene = repo / "examples" / "scenes" / "bar-drop.json"
    wav = tmp_path / "cli.wav"
    r = run([cli, "render", scene, "-o", wav, "--duration", "0.5", "--cache", cache_dir, "--quiet"])
    assert r.returncode == 0, r.stderr
    session = strike.Session()
    for _ in range(2):
        result = strike.render(scene, duration=0.5, cache=cache_dir, session=session)
        result.save(tmp_path / "py.wav")
        assert (tmp_path / "py.wav").read_bytes() == wav.read_bytes()
    stats = session.stats
    assert stats["hits"] >= 2 and stats["misses"] >= 1, stats  # the bar's hull and bank surface, reused
    assert 0 < stats["bytes"] <= stats["max_bytes"] == 64 << 20
    tiny = strike.Session(max_bytes=1)
    for _ in range(2):
        strike.render(scene, duration=0.5, cache=cache_dir, session=tiny).save(tmp_path / "tiny.wav")
        assert (tmp_path / "tiny.wav").read_bytes() == wav.read_bytes()
        assert tiny.stats["entries"] == 1
    assert tiny.stats["evicted"] >= 2
