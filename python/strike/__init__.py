# SPDX-License-Identifier: MIT
"""Strike: rigid-body impact sound synthesis, from Python.

The same engine as the ``strike`` command line (the C++ libraries, through the pybind11 module
``strike._strike``), so the same inputs give the same samples and the same WAV bytes::

    import strike
    bank = strike.modes("box:0.3,0.02,0.02", material="steel", order=2)
    bank.frequencies_hz, bank.decay_per_s            # numpy arrays
    bank.save("bar.modes")
    audio = strike.hit(bank, at=(0.15, 0, 0.01), impulse=(0, 0, -0.01), rate=48000)  # float32
    result = strike.render("examples/scenes/bar-drop.json")   # or a dict in the scene format
    result.audio, result.rate, result.events, result.metadata

Units are SI. Output sample 1.0 is 20 Pa at the listener (120 dB SPL), as in the CLI.
Bad input raises :class:`InputError` (a ``ValueError``) whose message names the file, key and
value, exactly as the CLI prints it. The GIL is released while modes are solved and sound is
rendered, so threads run in parallel.
"""
from __future__ import annotations

import json
import os
from typing import Any, Mapping, Optional, Sequence, Union

import sys as _sys

try:
    import numpy as np
except ImportError as _missing:  # another python3 first on PATH (pyenv, conda, a bare venv)
    raise ImportError(
        f"strike needs numpy, which {_sys.executable} (Python {_sys.version.split()[0]}) cannot import. "
        "Use Debian's python3 with its numpy (apt install python3-numpy; /usr/bin/python3), or a venv that "
        "sees it: /usr/bin/python3 -m venv --system-site-packages VENV, then, in the Strike repository, "
        "VENV/bin/pip install --no-build-isolation ./python (docs/install.md)") from _missing
try:
    from . import _strike
except ImportError as _missing:
    raise ImportError(
        f"strike's compiled module strike._strike does not load in {_sys.executable} "
        f"(Python {_sys.version.split()[0]}): {_missing}. It is built for the Python that built it; "
        "install the package with this one: python3 -m pip install --no-build-isolation ./python "
        "(docs/install.md)") from _missing
from ._version import __version__

Bank = _strike.Bank
InputError = _strike.InputError
Session = _strike.Session
Session.__doc__ = """What renders rebuild from identical inputs, kept between the renders given it:
each body's convex hull and each cached bank's surface and locator (~3 ms of a 40 ms render of
three small objects). ``render(scene, session=s)``. Keyed by content, so the bytes are the same
with or without it, warm or cold. Bounded: ``Session(max_bytes=64 MiB)`` drops its least recently
used entries beyond that. ``stats``: entries, bytes, max_bytes, hits, misses, evicted. A render
holds what it uses, so a session may be shared between threads."""

__all__ = ["Bank", "InputError", "RenderResult", "Session", "modes", "hit", "render", "similar", "material", "material_names",
           "write_audio", "default_cache_dir", "__version__"]

_MATERIAL_KEYS = ("youngs_pa", "poisson", "density_kg_m3", "rayleigh_stiffness", "rayleigh_mass")


def _bad(message: str) -> InputError:
    return InputError(message)


def _number(name: str, value: Any, low: float, high: float, rule: str) -> float:
    """``value`` as a float in [low, high], or InputError naming ``name`` and the value."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise _bad(f"{name} = {value!r} (must be a number)") from None
    if not (low <= number <= high):
        raise _bad(f"{name} = {value!r} ({rule})")
    return number


def _vector3(name: str, value: Any) -> Optional[tuple]:
    if value is None:
        return None
    try:
        v = tuple(float(x) for x in value)
    except (TypeError, ValueError):
        raise _bad(f"{name} = {value!r} (must be three numbers x, y, z)") from None
    if len(v) != 3 or not all(np.isfinite(v)):
        raise _bad(f"{name} = {value!r} (must be three finite numbers x, y, z)")
    return v


def material(name: str) -> dict:
    """The built-in material ``name`` (``strike modes --list-materials``) as a dict:
    name, youngs_pa, poisson, density_kg_m3, rayleigh_stiffness (s), rayleigh_mass (1/s)."""
    return _strike.material(name)


def material_names() -> list:
    """Names of the built-in materials."""
    return list(_strike.material_names())


def _material(value: Union[str, Mapping[str, Any]]) -> dict:
    """A material name, or a dict: a ``name`` of the table with overrides, or all of
    youngs_pa, poisson, density_kg_m3 (Rayleigh terms default to 0), as ``strike modes`` takes them."""
    if isinstance(value, str):
        return _strike.material(value)
    if not isinstance(value, Mapping):
        raise _bad(f"material = {value!r} (must be a material name or a dict)")
    unknown = sorted(set(value) - set(_MATERIAL_KEYS) - {"name"})
    if unknown:
        raise _bad(f"material: unknown key '{unknown[0]}' (known: name, {', '.join(_MATERIAL_KEYS)})")
    if "name" in value and value["name"] in _strike.material_names():
        out = _strike.material(value["name"])
        if set(value) - {"name"}:
            out["name"] = value["name"] + " (modified)"
    else:
        missing = [k for k in _MATERIAL_KEYS[:3] if k not in value]
        if missing:
            raise _bad(f"material: missing '{missing[0]}' (give a built-in name, or youngs_pa, poisson and density_kg_m3)")
        out = {"name": value.get("name", "custom"), "rayleigh_stiffness": 0.0, "rayleigh_mass": 0.0}
    for key in _MATERIAL_KEYS:
        if key in value:
            out[key] = value[key]
    out["youngs_pa"] = _number("material.youngs_pa", out["youngs_pa"], 1e-300, float("inf"), "must be > 0")
    poisson = _number("material.poisson", out["poisson"], -1.0, 0.5, "must be in (-1, 0.5); 0.5 is incompressible")
    if poisson in (-1.0, 0.5):
        raise _bad(f"material.poisson = {value['poisson']!r} (must be in (-1, 0.5); 0.5 is incompressible)")
    out["density_kg_m3"] = _number("material.density_kg_m3", out["density_kg_m3"], 1e-300, float("inf"), "must be > 0")
    out["rayleigh_stiffness"] = _number("material.rayleigh_stiffness", out["rayleigh_stiffness"], 0, float("inf"), "must be >= 0")
    out["rayleigh_mass"] = _number("material.rayleigh_mass", out["rayleigh_mass"], 0, float("inf"), "must be >= 0")
    return out


def modes(mesh: Union[str, os.PathLike], material: Union[str, Mapping[str, Any]] = "steel", order: Optional[int] = None,
          tolerance: Optional[float] = None, size: Optional[float] = None, max_freq: float = 20000.0,
          max_modes: int = 200, max_tets: Optional[int] = None, error_estimate: Optional[bool] = None,
          transfer: bool = True) -> Bank:
    """Computes an object's free vibration modes, as ``strike modes MESH -o BANK.modes`` does.

    mesh: a surface mesh (.obj .stl .ply), a tet mesh (.msh, TetGen .node/.ele) or a primitive in
        metres centred at the origin: ``box:LX,LY,LZ``, ``sphere:R``, ``cylinder:R,H``.
    material: a built-in name (:func:`material_names`) or a dict (see :func:`material`).
    order: 1 (Tet4) or 2 (Tet10); default from the shape, as ``strike modes`` without ``--order``
        (Tet10 for thin walls, plates and bars, Tet4 for solids; a tet file keeps its own).
        Not with ``tolerance``.
    tolerance: relative frequency error (0.01 = 1 %); picks the cheapest order and size whose
        estimated error meets it (``--tolerance``).
    size: target tet edge, m; default chosen from the object's size.
    max_freq: keep every mode up to this, Hz. max_modes: but at most this many.
    max_tets: refuse meshes with more tets (memory cap). error_estimate: default on for primitives
        and surfaces, as in the CLI.
    transfer: solve each mode's acoustic transfer (default, as the CLI; False: ``--no-transfer``,
        each mode heard at its direction-averaged level, docs/listener.md).

    Returns a :class:`Bank`: ``frequencies_hz``, ``decay_per_s`` (numpy), ``save(path)``,
    ``Bank.load(path)``. The GIL is released during the solve; solves in several threads of one
    process take turns (ARPACK is not re-entrant), processes solve in parallel.
    """
    mesh = os.fspath(mesh)
    mat = _material(material)
    if tolerance is not None:
        if order is not None or size is not None:
            raise _bad("tolerance chooses order and size itself; give one or the other")
        if error_estimate is False:
            raise _bad("tolerance needs the error estimate; drop error_estimate=False")
        tolerance = _number("tolerance", tolerance, 1e-300, float("inf"), "must be > 0")
    if order is not None and (order not in (1, 2) or isinstance(order, bool)):
        raise _bad(f"order = {order!r} (must be 1 or 2)")
    size_m = 0.0 if size is None else _number("size", size, 1e-300, float("inf"), "must be > 0 metres")
    max_freq = _number("max_freq", max_freq, 1e-300, float("inf"), "must be > 0 Hz")
    if not isinstance(max_modes, int) or not (1 <= max_modes <= 100000):
        raise _bad(f"max_modes = {max_modes!r} (must be 1 to 100000)")
    if max_tets is None:
        max_tets = _strike.default_max_tets()
    if not isinstance(max_tets, int) or max_tets < 1:
        raise _bad(f"max_tets = {max_tets!r} (must be >= 1)")
    order = 0 if order is None else int(order)  # 0: the library's automatic order
    return _strike.modes(mesh, mat, order, size_m, max_freq, max_modes, max_tets, error_estimate, tolerance,
                         bool(transfer))


def hit(bank: Union[Bank, str, os.PathLike], at: Optional[Sequence[float]] = None, impulse: Optional[Sequence[float]] = None,
        rate: float = 48000, duration: float = 2.0, vertex: Optional[int] = None, distance: float = 1.0,
        gain: float = 1.0, contact_time: Optional[float] = None, striker: str = "steel",
        striker_radius: float = 0.005, info: bool = False):
    """Strikes a bank's object once and renders what a listener hears, as ``strike hit`` does
    (same samples for the same arguments).

    bank: a :class:`Bank` or a bank file path.
    at: strike the surface point nearest to (x, y, z), m, mesh frame; or ``vertex``: a surface
        vertex index; neither: the vertex that excites the modes most.
    impulse: (x, y, z) N s; default 0.01 N s into the surface along its normal.
    rate (Hz), duration (s), distance (listener, m; sets gain and delay), gain.
    contact_time: force pulse length, s (0 = ideal impulse); default from Hertz theory with a
        ``striker`` sphere (material name) of ``striker_radius`` m.

    Returns a 1-D numpy float32 array (1.0 = 20 Pa); with ``info=True`` also a dict (vertex,
    point_m, impulse_n_s, contact_time_s, peak, clipped_samples). The GIL is released.
    """
    if not isinstance(bank, Bank):
        bank = Bank.load(os.fspath(bank))
    if vertex is not None and at is not None:
        raise _bad("give vertex or at, not both")
    if vertex is not None and (not isinstance(vertex, int) or not (0 <= vertex < bank.surface_vertex_count)):
        raise _bad(f"vertex = {vertex!r} (the bank has surface vertices 0 to {bank.surface_vertex_count - 1})")
    duration = _number("duration", duration, 1e-300, 3600, "must be in (0, 3600] s")
    rate = _number("rate", rate, 8000, 384000, "must be 8000 to 384000 Hz")
    distance = _number("distance", distance, 1e-300, float("inf"), "must be > 0 m")
    gain = _number("gain", gain, 1e-300, float("inf"), "must be > 0")
    striker_radius = _number("striker_radius", striker_radius, 1e-300, float("inf"), "must be > 0 m")
    if contact_time is not None:
        contact_time = _number("contact_time", contact_time, 0, 1, "must be in [0, 1) s")
        if contact_time == 1:
            raise _bad(f"contact_time = {contact_time!r} (must be in [0, 1) s)")
    audio, details = _strike.hit(bank, vertex, _vector3("at", at), _vector3("impulse", impulse), duration, rate, distance,
                                 gain, contact_time, striker, striker_radius)
    return (audio, details) if info else audio


class RenderResult:
    """What :func:`render` returns.

    audio: numpy float32, shape (frames,) for mono (1.0 = 20 Pa at the listener times gain).
    rate: sample rate, Hz.
    events: numpy structured array, one row per contact (the columns of ``--events``; body
        indices into ``metadata["bodies"]``, -1 for the ground; vectors as (n, 3) fields, e.g.
        ``slip_velocity_m_s``; ``motion`` is "rest", "rolling", "sliding" or "rolling+sliding").
    metadata: dict: the scene, version, bodies, counts (banks cached/computed, events, modes),
        peak level and timings in seconds.
    """

    def __init__(self, native: Any, scene: Union[str, dict]):
        self._native = native
        self.audio: np.ndarray = native.audio
        self.rate: float = native.rate
        self._events: Optional[np.ndarray] = None
        self.metadata: dict = dict(native.report, strike_version=__version__)
        if isinstance(scene, dict):
            self.metadata["scene"] = scene

    @property
    def events(self) -> np.ndarray:
        """The contact events (built on first use: a render may have millions)."""
        if self._events is None:
            self._events = self._native.events
        return self._events

    def save(self, path: Union[str, os.PathLike], format: Optional[str] = None) -> None:
        """Writes the sound atomically, as ``strike render -o`` does: .wav (default float) or
        .flac (default pcm24); ``format`` = pcm16, pcm24 or float. Same bytes as the CLI."""
        path = os.fspath(path)
        if format is None:
            format = "pcm24" if path.endswith(".flac") else "float"
        self._native.save(path, format)

    def save_events_csv(self, path: Union[str, os.PathLike]) -> None:
        """Writes the contact events as ``strike render --events`` does."""
        self._native.save_events_csv(os.fspath(path))


def default_cache_dir() -> str:
    """$STRIKE_CACHE_DIR, else $XDG_CACHE_HOME/strike, else ~/.cache/strike (as the CLI)."""
    return _strike.default_cache_dir()


def similar(bank: Bank, scale: float = 1.0, material: Union[str, Mapping[str, Any], None] = None,
            max_freq: Optional[float] = None, mesh: Optional[str] = None) -> Bank:
    """The bank of ``bank``'s object scaled uniformly by ``scale`` and made of ``material`` (same
    Poisson ratio), without a solve: exact similarity of linear elasticity. Eigenvalues scale by
    (E'/E) / ((rho'/rho) scale^2), mass-normalized shapes by 1 / sqrt((rho'/rho) scale^3); the
    new material's Rayleigh damping applies. ``max_freq`` (default the bank's) is the new
    cut-off; it may not reach past the band that was solved. ``mesh`` names the new object
    (e.g. the scaled primitive spec). Equals a direct solve of the scaled mesh to solver
    precision when the mesh is the scaled mesh (``size`` scaled too)."""
    mat = bank.material if material is None else _material(material)
    scale = _number("scale", scale, 1e-300, float("inf"), "must be > 0")
    max_freq = bank.max_freq_hz if max_freq is None else _number("max_freq", max_freq, 1e-300, float("inf"), "must be > 0 Hz")
    return bank.similar(scale, mat, max_freq, mesh if mesh is not None else f"{bank.mesh_source} scaled {scale!r}")


def render(scene: Union[str, os.PathLike, Mapping[str, Any]], rate: Optional[float] = None,
           duration: Optional[float] = None, gain: float = 1.0, cache: Union[str, os.PathLike, None, bool] = True,
           base_dir: Union[str, os.PathLike, None] = None, max_tets: Optional[int] = None,
           max_events: Optional[int] = None, similar: bool = False, session: Optional[Session] = None,
           transfer: bool = True, solve_threads: int = 0,
           output: str = "mono", hrtf: Union[str, os.PathLike, None] = None) -> RenderResult:
    """Renders a collision scene, as ``strike render SCENE.json -o OUT.wav`` does (same engine,
    same samples; :meth:`RenderResult.save` writes the CLI's bytes).

    scene: a scene file path, or a dict in the scene format (docs/scene-format.md); a dict's
        relative mesh and bank paths resolve against ``base_dir`` (default: the working folder).
    rate, duration: override the scene's sample_rate and duration.
    cache: the mode bank cache folder; True (default): :func:`default_cache_dir`; None or False:
        no cache (``--no-cache``).
    similar: exact similarity reuse (``--similar``, docs/datasets.md): one eigen-solve per shape at
        unit size, scaled to every size and material of its Poisson ratio; the same bytes as
        ``strike render --similar``, which differ from a render without it in some modes' polarity.
    transfer: banks this render computes get an acoustic transfer (default, as the CLI; False:
        ``--no-transfer``). Banks given in the scene are used as they are.
    session: a :class:`Session` whose hulls and bank surfaces this render reuses and adds to
        (renders in a loop: ~3 ms each of a small scene); the same bytes without it.
    solve_threads: how many of the banks this render computes are solved at once, each on a thread
        (0, default: one per core, as far as the memory forecast allows; 1: one after another, as
        the batch's workers do, which use every core already). The same bytes either way.
    output: the channels (``--output``, docs/listener.md): "mono" (default), "stereo", "binaural"
        (left and right ear), or "ambix1", "ambix2", "ambix3" (AmbiX: ACN order, SN3D); audio is
        then (frames, channels).
    hrtf: the binaural output's head-related responses (``--hrtf``): an AES69 SOFA file; None
        (default): the MIT KEMAR set of Debian's libmysofa.
        The listener's orientation is the scene's ``listener.orientation`` or ``listener.look_at``.
    The GIL is released during the render.
    """
    rate_hz = 0.0 if rate is None else _number("rate", rate, 8000, 384000, "must be 8000 to 384000 Hz")
    duration_s = 0.0 if duration is None else _number("duration", duration, 1e-300, 3600, "must be in (0, 3600] s")
    gain = _number("gain", gain, 1e-300, float("inf"), "must be > 0")
    if cache is True:
        cache_dir = default_cache_dir()
    elif cache is None or cache is False:
        cache_dir = ""
    else:
        cache_dir = os.fspath(cache)
    if max_tets is None:
        max_tets = _strike.default_max_tets()
    if max_events is None:
        max_events = _strike.default_max_events()
    if not isinstance(max_tets, int) or max_tets < 1:
        raise _bad(f"max_tets = {max_tets!r} (must be >= 1)")
    if not isinstance(max_events, int) or max_events < 1:
        raise _bad(f"max_events = {max_events!r} (must be >= 1)")
    if not isinstance(solve_threads, int) or isinstance(solve_threads, bool) or not 0 <= solve_threads <= 1024:
        raise _bad(f"solve_threads = {solve_threads!r} (must be 0 to 1024)")
    if isinstance(scene, Mapping):
        scene = dict(scene)
        # Why a file name: it anchors relative paths and names the source in messages.
        anchor = os.path.join(os.path.abspath(os.fspath(base_dir or ".")), "<scene dict>")
        try:
            native = _strike.render_text(json.dumps(scene), anchor, rate_hz, duration_s, gain, cache_dir, max_tets,
                                         max_events, bool(similar), bool(transfer), session, solve_threads, str(output),
                                         "" if hrtf is None else os.fspath(hrtf))
        except InputError as error:
            # The anchor is no file: messages name the dict (and where its paths resolve) instead.
            message = str(error)
            if message.startswith(anchor):
                where = "scene dict" if base_dir is None else f"scene dict (paths from {os.fspath(base_dir)})"
                message = where + message[len(anchor):]
            raise InputError(message) from None
        return RenderResult(native, scene)
    path = os.fspath(scene)
    native = _strike.render_file(path, rate_hz, duration_s, gain, cache_dir, max_tets, max_events, bool(similar),
                                 bool(transfer), session, solve_threads, str(output),
                                 "" if hrtf is None else os.fspath(hrtf))
    return RenderResult(native, path)


def write_audio(path: Union[str, os.PathLike], audio: np.ndarray, rate: float, format: Optional[str] = None) -> None:
    """Writes samples (float32, 1.0 = full scale; shape (frames,) or (frames, channels))
    atomically with the CLI's writer: .wav (default float) or .flac (default pcm24)."""
    path = os.fspath(path)
    if format is None:
        format = "pcm24" if path.endswith(".flac") else "float"
    _strike.write_audio(path, np.asarray(audio, dtype=np.float32), float(rate), format)


def __dir__() -> list:
    """What the package offers (PEP 562): __all__ and its modules, not the names it imports."""
    return sorted(__all__ + [name for name in ("batch", "manifest", "random_scenes") if name in globals()])
