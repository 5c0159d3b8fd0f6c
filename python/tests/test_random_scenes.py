# SPDX-License-Identifier: MIT
# Randomized scenes: a spec, a seed and an index give one scene dict, bit for bit, every time.
import json
import math
import subprocess
import sys

import pytest

import strike
from strike.random_scenes import SpecError, draw_scene


@pytest.fixture(scope="module")
def spec(repo):
    return json.loads((repo / "examples" / "python" / "random-drops.json").read_text())


def test_same_seed_and_index_regenerate_bit_identically(spec):
    scenes = [json.dumps(draw_scene(spec, 7, i)) for i in range(50)]
    assert scenes == [json.dumps(draw_scene(spec, 7, i)) for i in range(50)]
    # Each scene stands alone: drawing scene 31 by itself gives what the sequence gave.
    assert json.dumps(draw_scene(spec, 7, 31)) == scenes[31]
    assert len(set(scenes)) == 50 and json.dumps(draw_scene(spec, 8, 0)) != scenes[0]
    # In a fresh interpreter too (no state carried between processes).
    code = ("import json, sys; from strike.random_scenes import draw_scene; "
            "print(json.dumps(draw_scene(json.load(open(sys.argv[1])), 7, 31)))")
    r = subprocess.run([sys.executable, "-c", code, "examples/python/random-drops.json"], capture_output=True, text=True,
                       cwd=pytest.importorskip("conftest").REPO, env={"PYTHONPATH": ":".join(sys.path)})
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == scenes[31]


def test_draws_follow_their_distributions(spec):
    scenes = [draw_scene(spec, 1, i) for i in range(400)]
    counts = [len(s["objects"]) for s in scenes]
    assert set(counts) == {2, 3} and abs(counts.count(2) / 400 - 0.5) < 0.1  # binomial sd 0.025
    objects = [o for s in scenes for o in s["objects"]]
    heights = [o["position"][2] for o in objects]
    assert min(heights) >= 0.05 and max(heights) < 0.3
    assert abs(sum(heights) / len(heights) - 0.175) < 0.01  # uniform mean, sd of the mean ~0.003
    for o in objects:
        w, x, y, z = o["orientation"]
        assert math.isclose(w * w + x * x + y * y + z * z, 1.0, rel_tol=1e-12)
    # Scale multiplies the primitive's numbers: a 0.7-scaled sphere:0.03 has radius 0.021.
    radii = {float(o["mesh"].split(":")[1]) for o in objects if o["mesh"].startswith("sphere:")}
    assert radii == {0.021, 0.03, 0.042}
    assert {o["material"] for o in objects} == {"steel", "aluminium", "glass", "wood", "ceramic"}
    assert [o["name"] for o in scenes[0]["objects"]][:2] == ["object-0", "object-1"]


def test_a_drawn_scene_renders_and_bad_specs_name_the_key(spec, cache_dir):
    scene = draw_scene(spec, 3, 0)
    scene["duration"] = 0.2
    for o in scene["objects"]:  # small and fast for the test
        o["mesh"] = "box:0.1,0.02,0.01"
    result = strike.render(scene, cache=cache_dir)
    assert result.audio.shape == (9600,)
    with pytest.raises(SpecError, match=r"objects.each.position\[2\].uniform = \[0.1\]"):
        draw_scene({"objects": {"count": 1, "each": {"mesh": "sphere:0.1", "position": [0, 0, {"uniform": [0.1]}]}}}, 0, 0)
    with pytest.raises(SpecError, match=r"scale: mesh 'bowl.obj' is not a primitive"):
        draw_scene({"objects": [{"mesh": "bowl.obj", "scale": 2}]}, 0, 0)


def test_one_manifest_line_holds_a_randomized_dataset(repo, tmp_path):
    from strike.manifest import ManifestError, read_manifest
    manifest = tmp_path / "dataset.jsonl"
    spec_path = repo / "examples" / "python" / "random-drops.json"
    manifest.write_text(json.dumps({"id": "drops", "random": str(spec_path), "seed": 7, "count": 1000, "first": 5}) + "\n")
    jobs = read_manifest(str(manifest))
    assert [j.id for j in jobs[:2]] == ["drops-000005", "drops-000006"] and len(jobs) == 1000
    spec = json.loads(spec_path.read_text())
    assert jobs[26].scene == draw_scene(spec, 7, 31) and jobs[26].seed == 7 and jobs[26].parameters == {"index": 31}
    manifest.write_text(json.dumps({"random": str(spec_path), "seed": 7, "count": 0}) + "\n")
    with pytest.raises(ManifestError, match=r"dataset.jsonl:1: error: count = 0 \(must be an integer >= 1\)"):
        read_manifest(str(manifest))
