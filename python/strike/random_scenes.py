# SPDX-License-Identifier: MIT
"""Randomized scenes, reproducibly (docs/datasets.md).

A *random spec* is a scene template (the scene format) in which any value may be a distribution:

    {"uniform": [a, b]}        a float in [a, b)
    {"loguniform": [a, b]}     exp(uniform(log a, log b)), a, b > 0
    {"normal": [mean, sd]}
    {"int": [a, b]}            an integer in [a, b], both included
    {"choice": [v1, v2, ...]}  one of the values (each may itself hold distributions)
    {"quaternion": "uniform"}  a uniformly distributed rotation [w, x, y, z] (Shoemake 1992)

and where "objects" may be {"count": DIST, "each": OBJECT}: that many objects, each drawn from the
OBJECT template (named "NAME-0", "NAME-1", ... after its "name", default "object"). An object may
carry "scale": DIST, which multiplies the numbers of a primitive mesh ("box:LX,LY,LZ",
"sphere:R", "cylinder:R,H"); so 4 shapes at random sizes need 4 entries.

Scene ``index`` of a dataset with ``seed`` draws from its own generator, Python's Mersenne Twister
seeded with the string "strike/SEED/INDEX" (stable across Python versions, and independent of the
other scenes, so any slice regenerates alone); floats are kept whole in the JSON (shortest
round-trip repr). Same spec, seed and index: the same scene dict, bit for bit.
"""
from __future__ import annotations

import copy
import math
import random
from typing import Any

_DISTRIBUTIONS = ("uniform", "loguniform", "normal", "int", "choice", "quaternion")
_PRIMITIVES = ("box", "sphere", "cylinder")


class SpecError(ValueError):
    """A random spec that cannot be drawn from; the message names the key path and value."""


def _is_distribution(value: Any) -> bool:
    return isinstance(value, dict) and len(value) == 1 and next(iter(value)) in _DISTRIBUTIONS


def _pair(where: str, kind: str, args: Any) -> tuple:
    if not (isinstance(args, list) and len(args) == 2 and all(isinstance(a, (int, float)) for a in args)):
        raise SpecError(f"{where}.{kind} = {args!r} (must be two numbers [a, b])")
    return float(args[0]), float(args[1])


def _draw_one(rng: random.Random, dist: dict, where: str) -> Any:
    kind, args = next(iter(dist.items()))
    if kind == "uniform":
        a, b = _pair(where, kind, args)
        return a + (b - a) * rng.random()
    if kind == "loguniform":
        a, b = _pair(where, kind, args)
        if not (a > 0 and b > 0):
            raise SpecError(f"{where}.loguniform = {args!r} (bounds must be > 0)")
        return math.exp(math.log(a) + (math.log(b) - math.log(a)) * rng.random())
    if kind == "normal":
        mean, sd = _pair(where, kind, args)
        return rng.gauss(mean, sd)
    if kind == "int":
        a, b = _pair(where, kind, args)
        if a != int(a) or b != int(b) or a > b:
            raise SpecError(f"{where}.int = {args!r} (must be integers a <= b)")
        return int(a) + int(rng.random() * (int(b) - int(a) + 1))
    if kind == "choice":
        if not (isinstance(args, list) and args):
            raise SpecError(f"{where}.choice = {args!r} (must be a non-empty list)")
        k = int(rng.random() * len(args))
        return _draw(rng, args[k], f"{where}.choice[{k}]")
    if kind == "quaternion":
        if args != "uniform":
            raise SpecError(f"{where}.quaternion = {args!r} (only \"uniform\")")
        # Shoemake, "Uniform random rotations", Graphics Gems III (1992).
        u1, u2, u3 = rng.random(), rng.random(), rng.random()
        a, b = math.sqrt(1 - u1), math.sqrt(u1)
        return [b * math.cos(2 * math.pi * u3), a * math.sin(2 * math.pi * u2), a * math.cos(2 * math.pi * u2),
                b * math.sin(2 * math.pi * u3)]
    raise AssertionError(kind)


def _draw(rng: random.Random, value: Any, where: str) -> Any:
    """``value`` with every distribution replaced by a draw, depth first in key order as written."""
    if _is_distribution(value):
        return _draw_one(rng, value, where)
    if isinstance(value, dict):
        return {k: _draw(rng, v, f"{where}.{k}" if where else k) for k, v in value.items()}
    if isinstance(value, list):
        return [_draw(rng, v, f"{where}[{i}]") for i, v in enumerate(value)]
    return value


def _scaled_mesh(mesh: Any, scale: float, where: str) -> str:
    kind, _, numbers = str(mesh).partition(":")
    if kind not in _PRIMITIVES:
        raise SpecError(f"{where}.scale: mesh {mesh!r} is not a primitive (box:, sphere:, cylinder:)")
    if not (isinstance(scale, (int, float)) and scale > 0):
        raise SpecError(f"{where}.scale = {scale!r} (must be > 0)")
    try:
        values = [float(x) * scale for x in numbers.split(",")]
    except ValueError:
        raise SpecError(f"{where}.mesh = {mesh!r} (not numbers after '{kind}:')") from None
    # 12 significant digits: "sphere:0.021", not "sphere:0.020999999999999998" (still exact per draw).
    return kind + ":" + ",".join(format(v, ".12g") for v in values)


def _object(rng: random.Random, template: Any, where: str) -> dict:
    obj = _draw(rng, template, where)
    if not isinstance(obj, dict):
        raise SpecError(f"{where} = {template!r} (must be an object)")
    if "scale" in obj:
        scale = obj.pop("scale")
        obj["mesh"] = _scaled_mesh(obj.get("mesh"), scale, where)
    return obj


def draw_scene(spec: dict, seed: int, index: int) -> dict:
    """Scene ``index`` of the dataset (``spec``, ``seed``): a plain scene dict for strike.render."""
    if not isinstance(spec, dict):
        raise SpecError(f"random spec = {spec!r} (must be a JSON object)")
    if isinstance(seed, bool) or not isinstance(seed, int) or isinstance(index, bool) or not isinstance(index, int) or index < 0:
        raise SpecError(f"seed = {seed!r}, index = {index!r} (must be integers, index >= 0)")
    rng = random.Random(f"strike/{seed}/{index}")
    spec = copy.deepcopy(spec)
    objects = spec.pop("objects", [])
    scene = _draw(rng, spec, "")
    if isinstance(objects, dict) and set(objects) == {"count", "each"}:
        count = _draw(rng, objects["count"], "objects.count")
        if isinstance(count, bool) or not isinstance(count, int) or count < 0:
            raise SpecError(f"objects.count drew {count!r} (must be an integer >= 0)")
        base = objects["each"].get("name", "object") if isinstance(objects["each"], dict) else "object"
        drawn = []
        for k in range(count):
            obj = _object(rng, objects["each"], f"objects.each")
            obj["name"] = f"{base}-{k}"
            drawn.append(obj)
        scene["objects"] = drawn
    elif isinstance(objects, list):
        scene["objects"] = [_object(rng, o, f"objects[{k}]") for k, o in enumerate(objects)]
    else:
        raise SpecError(f"objects = {objects!r} (must be a list, or {{\"count\": ..., \"each\": ...}})")
    return scene
