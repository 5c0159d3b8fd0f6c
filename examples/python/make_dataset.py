#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""A small impact-sound dataset, notebook style: draw scenes, render them on Dask, plot them.

    /usr/bin/python3 examples/python/make_dataset.py [-o dataset/] [--count 12] [--workers 2]

Needs the strike package (docs/install.md) and Debian's python3-matplotlib. Each step is a cell:
run it top to bottom, or paste the cells into a notebook.
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys

import numpy as np

import strike
from strike.random_scenes import draw_scene

here = pathlib.Path(__file__).resolve().parent
parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
parser.add_argument("-o", dest="out", default="dataset", help="output folder (default dataset/)")
parser.add_argument("--count", type=int, default=12, help="scenes to render (default 12)")
parser.add_argument("--seed", type=int, default=2026, help="dataset seed (default 2026)")
parser.add_argument("--workers", type=int, default=2, help="local Dask workers (default 2)")
args = parser.parse_args()
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)

# %% 1. The dataset is a spec (distributions) + a seed: one manifest line.
spec_path = here / "random-drops.json"
spec = json.loads(spec_path.read_text())
print("scene 0 of the dataset:", json.dumps(draw_scene(spec, args.seed, 0))[:300], "...")
manifest = out / "manifest.jsonl"
manifest.write_text(json.dumps({"id": "drop", "random": str(spec_path), "seed": args.seed, "count": args.count}) + "\n")

# %% 2. Render it on a local Dask cluster (re-running this skips what is done).
renders = out / "renders"
subprocess.run([sys.executable, "-m", "strike", "batch", str(manifest), "-o", str(renders), "--workers", str(args.workers),
                "--cache", str(out / "bank-cache")], check=True)

def wav_samples(path):
    """The float32 samples of a WAV written by strike (RIFF, format 3, one data chunk)."""
    data = pathlib.Path(path).read_bytes()
    pos = 12
    while pos + 8 <= len(data):
        size = int.from_bytes(data[pos + 4:pos + 8], "little")
        if data[pos:pos + 4] == b"data":
            return np.frombuffer(data[pos + 8:pos + 8 + size], dtype="<f4")
        pos += 8 + size + (size & 1)
    raise ValueError(f"{path}: no data chunk")


# %% 3. Load the sounds and their metadata (what made each one).
items = []
for meta_path in sorted(renders.glob("*.json")):
    meta = json.loads(meta_path.read_text())
    items.append(meta)
print(f"{len(items)} renders; materials:",
      sorted({o["material"] for m in items for o in m["scene"]["objects"]}))


# %% 4. Spectrograms (matplotlib, headless), with the objects and materials as titles.
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

shown = items[:6]
fig, axes = plt.subplots(len(shown), 1, figsize=(8, 2.2 * len(shown)), squeeze=False)
for ax, meta in zip(axes[:, 0], shown):
    samples = wav_samples(renders / meta["audio"]["file"])
    rate = meta["audio"]["rate"]
    ax.set_facecolor("black")  # exact silence: log10(0) = -inf is not drawn
    with np.errstate(divide="ignore"):  # silent stretches: log10(0) is -inf, drawn as the floor
        ax.specgram(samples, NFFT=1024, Fs=rate, noverlap=768, cmap="magma", scale="dB", vmin=-160)
    ax.set_ylim(20, 16000)
    ax.set_yscale("symlog", linthresh=1000)
    title = ", ".join(f"{o['material']} {o['mesh']}" for o in meta["scene"]["objects"])
    ax.set_title(f"{meta['id']}: {title}", fontsize=8)
    ax.set_ylabel("Hz")
axes[-1, 0].set_xlabel("s")
fig.tight_layout()
figure = out / "spectrograms.png"
fig.savefig(figure, dpi=110)
print("wrote", figure)

# %% 5. One more sound from Python directly: strike the richest bank the dataset solved (a small
# sphere may have no mode below 20 kHz at all).
banks = {b["cache_key"] for m in items for b in m["banks"] if b["sounded"]}
banks = [strike.Bank.load(out / "bank-cache" / f"{key}.modes") for key in sorted(banks)]
bank = max(banks, key=lambda b: b.mode_count)
key = bank.content_hash
print(f"bank {bank.mesh_source} ({bank.material['name']}): {bank.mode_count} modes, lowest {bank.frequencies_hz[0]:.1f} Hz, decay {bank.decay_per_s[0]:.2f}/s")
tap = strike.hit(bank, rate=48000, duration=1.0)
strike.write_audio(out / "tap.wav", tap, 48000)
print("wrote", out / "tap.wav", f"(peak {np.abs(tap).max():.3g} = {20 * np.log10(np.abs(tap).max() * 20 / 20e-6):.0f} dB SPL)")
