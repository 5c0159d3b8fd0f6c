# SPDX-License-Identifier: MIT
"""Batch manifests: JSON lines, one render per line (docs/datasets.md).

Each line is a JSON object with exactly one of:

    "scene":    a scene file path or a scene dict;
    "template": a scene file path or dict in which every string "${NAME}" (the whole string) is
                replaced by the value of "parameters": {"NAME": value, ...} (any JSON value);
    "random":   a random spec file path or dict (strike.random_scenes) with "seed" and either
                "index" (one scene) or "count" (scenes "first" (default 0) to first+count-1, ids
                ID-000000, ID-000001, ... after the index: a dataset of 10^5 scenes is one line);

and optionally "id" (the output name, [A-Za-z0-9._-], default the line number as 000001),
"rate", "duration", "gain" (override the scene's), "seed" (recorded; required with "random"),
"output" (the channels, as ``strike render --output``: "mono" (default), "stereo", "binaural",
"ambix1", "ambix2", "ambix3") and "hrtf" (a SOFA file for "binaural"; default the MIT KEMAR set).
Relative paths (in the line and in an inline scene) resolve against the manifest's folder.
Blank lines and lines starting with # are skipped.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
from dataclasses import dataclass, field
from typing import Any, Optional

from .random_scenes import SpecError, draw_scene

_ID = re.compile(r"^[A-Za-z0-9._-]{1,200}$")
_KEYS = {"id", "scene", "template", "parameters", "random", "seed", "index", "count", "first", "rate", "duration", "gain",
         "output", "hrtf"}
_OUTPUTS = ("mono", "stereo", "binaural", "ambix1", "ambix2", "ambix3")
_PLACEHOLDER = re.compile(r"^\$\{([A-Za-z_][A-Za-z0-9_]*)\}$")


class ManifestError(ValueError):
    """A bad manifest line; the message reads "MANIFEST:LINE: error: KEY = VALUE (why)"."""


@dataclass
class Job:
    """One render of a batch: the resolved scene and everything that made it."""
    id: str
    line: int
    scene: dict                      # the scene dict handed to strike.render
    base_dir: str                    # relative mesh/bank paths in the scene resolve here
    source: dict                     # the manifest line as written
    parameters: dict = field(default_factory=dict)
    seed: Optional[int] = None
    rate: Optional[float] = None
    duration: Optional[float] = None
    gain: float = 1.0
    output: str = "mono"
    hrtf: Optional[str] = None       # absolute path, or None: the default set

    def key(self) -> str:
        """Hash of everything that decides the output: a done render with another key is redone."""
        decided = {"scene": self.scene, "base_dir": self.base_dir, "rate": self.rate, "duration": self.duration,
                   "gain": self.gain}
        if self.output != "mono" or self.hrtf is not None:  # mono keeps the keys it had
            decided.update(output=self.output, hrtf=self.hrtf)
        text = json.dumps(decided, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()


def _substitute(value: Any, parameters: dict, used: set, where: str) -> Any:
    if isinstance(value, str):
        m = _PLACEHOLDER.match(value)
        if m:
            if m.group(1) not in parameters:
                raise KeyError(f"{where}: template asks for ${{{m.group(1)}}}, not in parameters")
            used.add(m.group(1))
            return parameters[m.group(1)]
        return value
    if isinstance(value, dict):
        return {k: _substitute(v, parameters, used, f"{where}.{k}" if where else k) for k, v in value.items()}
    if isinstance(value, list):
        return [_substitute(v, parameters, used, f"{where}[{i}]") for i, v in enumerate(value)]
    return value


class _Files:
    """Scene, template and spec files read once per manifest."""

    def __init__(self, base_dir: str):
        self.base_dir = base_dir
        self.loaded: dict = {}

    def load(self, value: Any, where: str) -> tuple:
        """(dict, folder its relative paths resolve against)."""
        if isinstance(value, dict):
            return value, self.base_dir
        if not isinstance(value, str):
            raise ValueError(f"{where} = {value!r} (must be a file path or a JSON object)")
        path = value if os.path.isabs(value) else os.path.join(self.base_dir, value)
        if path not in self.loaded:
            try:
                with open(path, encoding="utf-8") as f:
                    self.loaded[path] = json.load(f)
            except OSError as e:
                raise ValueError(f"{where} = {value!r}: {path}: {e.strerror}") from None
            except json.JSONDecodeError as e:
                raise ValueError(f"{where} = {value!r}: {path}:{e.lineno}:{e.colno}: invalid JSON: {e.msg}") from None
        return self.loaded[path], os.path.dirname(os.path.abspath(path))


def _number(line: dict, key: str, low: float, high: float) -> Optional[float]:
    if key not in line:
        return None
    v = line[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not (low <= v <= high):
        raise ValueError(f"{key} = {json.dumps(v)} (must be a number in [{low:g}, {high:g}])")
    return float(v)


def parse_line(text: str, number: int, files: _Files) -> list:
    """The jobs of one manifest line (several for a random line with "count")."""
    line = json.loads(text)
    if isinstance(line, dict) and "random" in line and "count" in line:
        count, first = line["count"], line.get("first", 0)
        for key, value, low in (("count", count, 1), ("first", first, 0)):
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise ValueError(f"{key} = {json.dumps(value)} (must be an integer >= {low})")
        if "index" in line:
            raise ValueError("give index (one scene) or count (many), not both")
        base = {k: v for k, v in line.items() if k not in ("count", "first", "id")}
        prefix = line.get("id", f"{number:06d}")
        return [_parse_one(dict(base, index=i, id=f"{prefix}-{i:06d}"), number, files) for i in range(first, first + count)]
    for key in ("count", "first"):
        if isinstance(line, dict) and key in line:
            raise ValueError(f"{key} goes with a random spec")
    return [_parse_one(line, number, files)]


def _parse_one(line: Any, number: int, files: _Files) -> Job:
    if not isinstance(line, dict):
        raise ValueError(f"the line is {type(line).__name__}, not a JSON object")
    unknown = sorted(set(line) - _KEYS)
    if unknown:
        raise ValueError(f"unknown key '{unknown[0]}' (known: {', '.join(sorted(_KEYS))})")
    kinds = [k for k in ("scene", "template", "random") if k in line]
    if len(kinds) != 1:
        raise ValueError("give exactly one of scene, template, random" + (f" (got {', '.join(kinds)})" if kinds else ""))
    job_id = line.get("id", f"{number:06d}")
    if not isinstance(job_id, str) or not _ID.match(job_id):
        raise ValueError(f"id = {json.dumps(job_id)} (must be 1-200 of A-Z a-z 0-9 . _ -: it names the output files)")
    seed = line.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)):
        raise ValueError(f"seed = {json.dumps(seed)} (must be an integer)")
    parameters = {}
    if kinds[0] == "scene":
        scene, base = files.load(line["scene"], "scene")
    elif kinds[0] == "template":
        template, base = files.load(line["template"], "template")
        parameters = line.get("parameters", {})
        if not isinstance(parameters, dict):
            raise ValueError(f"parameters = {json.dumps(parameters)} (must be a JSON object)")
        used: set = set()
        try:
            scene = _substitute(template, parameters, used, "")
        except KeyError as e:
            raise ValueError(e.args[0]) from None
        unused = sorted(set(parameters) - used)
        if unused:
            raise ValueError(f"parameters.{unused[0]} = {json.dumps(parameters[unused[0]])}: the template has no ${{{unused[0]}}}")
    else:
        spec, base = files.load(line["random"], "random")
        index = line.get("index")
        if seed is None or index is None:
            raise ValueError("a random line needs \"seed\" and \"index\"")
        try:
            scene = draw_scene(spec, seed, index)
        except SpecError as e:
            raise ValueError(f"random: {e}") from None
        parameters = {"index": index}
    if "parameters" in line and kinds[0] != "template":
        raise ValueError("parameters go with a template")
    if "index" in line and kinds[0] != "random":
        raise ValueError("index goes with a random spec")
    output = line.get("output", "mono")
    if output not in _OUTPUTS:
        raise ValueError(f"output = {json.dumps(output)} (must be one of {', '.join(_OUTPUTS)})")
    hrtf = line.get("hrtf")
    if hrtf is not None:
        if not isinstance(hrtf, str) or not hrtf:
            raise ValueError(f"hrtf = {json.dumps(hrtf)} (must be a SOFA file path)")
        if output != "binaural":
            raise ValueError(f"hrtf = {json.dumps(hrtf)} goes with \"output\": \"binaural\"")
        hrtf = os.path.normpath(os.path.join(files.base_dir, hrtf))
    return Job(id=job_id, line=number, scene=scene, base_dir=base, source=line, parameters=parameters, seed=seed,
               rate=_number(line, "rate", 8000, 384000), duration=_number(line, "duration", 1e-9, 3600),
               gain=_number(line, "gain", 1e-300, 1e300) or 1.0, output=output, hrtf=hrtf)


def read_manifest(path: str) -> list:
    """Every job of a manifest; ManifestError naming the line, key and value on the first bad one."""
    base_dir = os.path.dirname(os.path.abspath(path))
    files = _Files(base_dir)
    jobs, seen = [], {}
    try:
        with open(path, encoding="utf-8") as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise ManifestError(f"{path}: error: {e.strerror}") from None
    for number, text in enumerate(lines, start=1):
        if not text.strip() or text.lstrip().startswith("#"):
            continue
        try:
            line_jobs = parse_line(text, number, files)
        except json.JSONDecodeError as e:
            raise ManifestError(f"{path}:{number}:{e.colno}: error: invalid JSON: {e.msg}") from None
        except ValueError as e:
            raise ManifestError(f"{path}:{number}: error: {e}") from None
        for job in line_jobs:
            if job.id in seen:
                raise ManifestError(f"{path}:{number}: error: id = \"{job.id}\" repeats line {seen[job.id]} (outputs would collide)")
            seen[job.id] = number
            jobs.append(job)
    if not jobs:
        raise ManifestError(f"{path}: error: no renders (every line is blank or a comment)")
    return jobs
