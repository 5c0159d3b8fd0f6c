# SPDX-License-Identifier: MIT
# Exact similarity (src/include/strike/precompute/similar_bank.hpp): a scaled, other-material copy of a
# solved bank against a direct solve of the scaled object, to solver precision.
import numpy as np
import pytest

import strike

STEEL = strike.material("steel")
# Another E and rho at steel's Poisson ratio (an aluminium-like solid).
SOFT = {"name": "soft", "youngs_pa": 7.0e10, "poisson": STEEL["poisson"], "density_kg_m3": 2700.0,
        "rayleigh_stiffness": 1e-7, "rayleigh_mass": 3.0}


def box(scale):
    return "box:" + ",".join(format(v * scale, ".12g") for v in (0.2, 0.03, 0.01))


def solve(scale, material, max_freq=80000.0, max_modes=8):
    # The mesh edge scales with the object, so the scaled mesh is the scaled reference mesh.
    return strike.modes(box(scale), material=material, size=0.01 * scale, max_modes=max_modes, max_freq=max_freq,
                        error_estimate=False)


@pytest.mark.parametrize("scale", [1.4, 0.6])
def test_a_scaled_softer_copy_equals_a_direct_solve(scale):
    reference = solve(1.0, "steel")
    direct = solve(scale, SOFT)
    derived = strike.similar(reference, scale, SOFT, mesh=box(scale))
    assert derived.mode_count == direct.mode_count == 8
    # lambda' = lambda (E'/E) / ((rho'/rho) s^2): equal to the solver's tolerance (ARPACK 1e-10).
    np.testing.assert_allclose(derived.eigenvalues, direct.eigenvalues, rtol=1e-10)  # measured: 2e-13
    ratio = (SOFT["youngs_pa"] / STEEL["youngs_pa"]) / (SOFT["density_kg_m3"] / STEEL["density_kg_m3"]) / scale ** 2
    np.testing.assert_allclose(derived.frequencies_hz[:3] ** 2, reference.frequencies_hz[:3] ** 2 * ratio, rtol=1e-3)
    # Damping is the new material's: decay = (a1 lambda + a2) / 2.
    np.testing.assert_allclose(derived.decay_per_s, direct.decay_per_s, rtol=1e-8)
    np.testing.assert_allclose(derived.mass_kg, direct.mass_kg, rtol=1e-12)
    np.testing.assert_allclose(derived.surface_positions_m, direct.surface_positions_m, rtol=1e-12, atol=1e-15)
    # Mass-normalized shapes, phi' = phi / sqrt((rho'/rho) s^3), up to each eigenvector's sign.
    for a, b in zip(derived.shapes, direct.shapes):
        sign = np.sign(np.sum(a * b))
        assert np.max(np.abs(a - sign * b)) <= 1e-6 * np.max(np.abs(b))  # float32 storage: 1e-7
    assert derived.mesh_source == box(scale) and derived.material["name"] == "soft"


def test_similarity_refuses_what_it_cannot_derive():
    reference = solve(1.0, "steel", max_freq=6000, max_modes=20)
    assert 2 <= reference.mode_count < 20, "the test needs a bank cut by frequency, not by count"
    with pytest.raises(strike.InputError, match=r"poisson = 0.1 differs"):
        strike.similar(reference, 1.0, dict(SOFT, poisson=0.1))
    # Twice the size halves the frequencies: modes between 3 and 6 kHz of the copy were never solved.
    with pytest.raises(strike.InputError, match=r"below the cut-off 6000 Hz: modes above it were never solved"):
        strike.similar(reference, 2.0)
    half = strike.similar(reference, 2.0, max_freq=3000)
    np.testing.assert_allclose(half.frequencies_hz, reference.frequencies_hz[:half.mode_count] / 2, rtol=1e-12)


TWO_BARS = {
    "sample_rate": 48000, "duration": 0.4, "gravity": [0, 0, -9.81],
    "listener": {"position": [0.0, -1.0, 0.5]}, "ground": {"material": "concrete"}, "max_modes": 30,
    "objects": [
        {"name": "steel", "mesh": "box:0.3,0.02,0.02", "material": "steel", "order": 2,
         "position": [0, 0, 0.1], "orientation": [0.99996, 0.0, 0.00873, 0.0]},
        # 1.4 x as long, softer and lighter, steel's Poisson ratio: the same normalized problem.
        {"name": "other", "mesh": "box:0.42,0.028,0.028", "order": 2,
         "material": {"name": "other", "youngs_pa": 1.1e11, "poisson": 0.29, "density_kg_m3": 4000,
                      "loss_factor": 3e-4},
         "position": [0, 0.2, 0.12], "orientation": [0.99996, 0.00873, 0.0, 0.0]},
    ],
}


def test_render_similar_solves_one_shape_once_and_the_cache_changes_no_byte(tmp_path):
    cold = strike.render(TWO_BARS, cache=tmp_path / "cache", similar=True)
    assert cold.metadata["objects_sounded"] == 2
    assert (cold.metadata["banks_computed"], cold.metadata["banks_scaled"]) == (1, 1)
    warm = strike.render(TWO_BARS, cache=tmp_path / "cache", similar=True)
    assert (warm.metadata["banks_computed"], warm.metadata["banks_cached"], warm.metadata["banks_scaled"]) == (0, 1, 1)
    assert cold.audio.tobytes() == warm.audio.tobytes()
    # Without --similar each bar is its own solve.
    direct = strike.render(TWO_BARS, cache=None)
    assert direct.metadata["banks_computed"] == 2
