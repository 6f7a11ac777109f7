"""Stepping, and the state's arrays in and out."""

import numpy as np
import pytest

import anima


def test_a_sheet_falls_under_gravity_and_keeps_its_pins():
    cloth = anima.Cloth.sheet(n=16, dt=2e-4)
    x0 = cloth.positions
    cloth.step(500)
    assert cloth.steps == 500 and cloth.time == pytest.approx(0.1)
    x = cloth.positions
    assert x[:, 2].mean() < x0[:, 2].mean() - 0.01  # z is up
    pinned = [0, 15]  # the corners (0, 0) and (15, 0)
    np.testing.assert_array_equal(x[pinned], x0[pinned])


def test_run_goes_to_the_scenes_end_and_matches_anima_run(assets, tmp_path):
    cloth = anima.load(assets / "scenes/standard-sheet-32.ron")
    cloth.run(0.05)
    summary = anima.run(assets / "scenes/standard-sheet-32.ron", tmp_path, duration=0.05)
    assert summary["steps"] == cloth.steps and summary["all_finite"]
    com = cloth.positions.mean(axis=0)  # equal masses: the mean is the centre of mass
    np.testing.assert_allclose(summary["center_of_mass"], com, rtol=0, atol=1e-12)
    assert (tmp_path / "summary.json").exists() and (tmp_path / "final.png").exists()


def test_a_run_exports_its_animation(assets, tmp_path):
    anima.run(assets / "scenes/stand.ron", tmp_path, duration=1.0, export="gltf")
    glb = (tmp_path / "animation.glb").read_bytes()
    assert glb[:4] == b"glTF" and len(glb) > 1000
    with pytest.raises(ValueError, match="out"):
        anima.run(assets / "scenes/stand.ron", export="gltf")
    with pytest.raises(ValueError, match="gltf"):
        anima.run(assets / "scenes/stand.ron", tmp_path, export="fbx")


def test_runs_are_deterministic():
    a, b = anima.Cloth.drape("sphere", 9), anima.Cloth.drape("sphere", 9)
    a.step(300)
    b.step(300)
    assert a.positions.tobytes() == b.positions.tobytes()


def test_a_state_round_trips_bit_for_bit():
    cloth = anima.Cloth.sheet(n=8, dt=2e-4)
    cloth.step(10)
    x, v = cloth.positions, cloth.velocities
    cloth.set_state(x, v)
    assert cloth.positions.tobytes() == x.tobytes() and cloth.velocities.tobytes() == v.tobytes()
    out = np.empty_like(x)
    cloth.read_positions(out)
    assert out.tobytes() == x.tobytes()
    cloth.read_velocities(out)
    assert out.tobytes() == v.tobytes()


def test_a_state_copied_into_another_cloth_steps_the_same():
    # Symplectic Euler keeps no history and the sheet's forces do not depend on time: a second sheet
    # given the first's state at step 50 goes on exactly as the first does.
    a, b = anima.Cloth.sheet(n=8, dt=2e-4), anima.Cloth.sheet(n=8, dt=2e-4)
    a.step(50)
    b.set_state(a.positions, a.velocities)
    a.step(50)
    b.step(50)
    assert a.positions.tobytes() == b.positions.tobytes()


def test_positions_set_are_where_the_cloth_steps_from():
    cloth = anima.Cloth.sheet(n=8, dt=2e-4)
    x = cloth.positions
    x[:, 2] += 1.0
    cloth.set_state(x)  # velocities kept (zero)
    cloth.step(1)
    assert cloth.positions[:, 2].min() > 2.0 and np.isfinite(cloth.positions).all()


def test_arrays_of_the_wrong_shape_or_layout_are_refused():
    cloth = anima.Cloth.sheet(n=8)
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        cloth.set_state(np.zeros((64, 2)))
    with pytest.raises(ValueError, match="expected 64 positions"):
        cloth.set_state(np.zeros((63, 3)))
    with pytest.raises(ValueError, match="C-contiguous"):
        cloth.set_state(np.asfortranarray(cloth.positions))
    with pytest.raises(ValueError, match="not finite"):
        x = cloth.positions
        x[3, 1] = np.nan
        cloth.set_state(x)
    with pytest.raises(ValueError, match="shape"):
        cloth.read_positions(np.zeros((10, 3)))
    with pytest.raises(ValueError, match="C-contiguous"):
        cloth.read_positions(np.zeros((64, 3), order="F"))


def test_an_adaptive_drape_changes_its_mesh_as_it_goes(assets):
    cloth = anima.load(assets / "oliveira/test-3-sphere-adaptive.ron")
    n0 = cloth.n
    cloth.run(0.3)  # the cloth has met the sphere and been refined where it bends
    assert cloth.n > n0
    assert cloth.positions.shape == (cloth.n, 3) and cloth.triangles.max() == cloth.n - 1


def test_figures_step_and_characters_walk(assets):
    standing = anima.load(assets / "scenes/stand.ron")
    head0 = standing.poses[0].copy()
    standing.step(20)
    assert standing.time == pytest.approx(20 * standing.dt)
    assert abs(standing.poses[0, 1] - head0[1]) < 0.05  # it stands
    walker = anima.load(assets / "scenes/walk.ron")
    x0 = walker.poses[:, 0].mean()
    walker.step(200)  # 10 s
    assert walker.poses[:, 0].mean() > x0 + 1.0


def test_a_character_scene_reports_its_evaluation(assets):
    summary = anima.run(assets / "scenes/walk.ron", duration=5.0)
    outcome = summary["evaluation"]["Walk"]
    assert outcome["distance"] > 1.0 and not outcome["fell"]
    walk = anima.walk(assets / "controllers/walk.ron", iterations=100)
    assert walk["iterations"] == 100 and walk["fitness"] == walk["distance"] > 0
