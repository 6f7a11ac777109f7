"""Every kind of file anima reads loads from Python, into the object its kind gives."""

import pytest

import anima


@pytest.mark.parametrize(
    "path, kind, particles",
    [
        ("flex3d/a2-8-toalha.par", "flex3d", None),  # a thesis script, verbatim
        ("flex3d/curtain.ron", "flex3d", None),  # a FLEX3D RON scene
        ("scenes/standard-sheet-32.ron", "sheet", 32 * 32),
        ("oliveira/test-3-sphere-5x5.ron", "oliveira", 25),
        ("oliveira/test-1-bunny-5x5.ron", "oliveira", 25),  # names an OBJ mesh
        ("oliveira/test-2-table-adaptive.ron", "oliveira", None),  # remeshed
    ],
)
def test_cloth_scenes_load_as_cloth(assets, path, kind, particles):
    cloth = anima.load(assets / path)
    assert isinstance(cloth, anima.Cloth)
    assert cloth.kind == kind
    assert cloth.time == 0.0 and cloth.steps == 0 and cloth.duration > 0
    x = cloth.positions
    assert x.shape == (cloth.n, 3) and x.dtype.name == "float64"
    if particles is not None:
        assert cloth.n == particles
    t = cloth.triangles
    assert t.shape[1] == 3 and t.dtype.name == "uint32" and t.max() < cloth.n


def test_objects_come_with_their_scene(assets):
    bunny = anima.load(assets / "oliveira/test-1-bunny-5x5.ron")
    obstacles = bunny.obstacles()
    assert any(v.shape[0] > 1000 for v, _ in obstacles)  # the Bunny's mesh
    assert all(v.shape[1] == 3 and t.shape[1] == 3 and t.max() < len(v) for v, t in obstacles)
    assert anima.Cloth.sheet(n=8).obstacles() == []


@pytest.mark.parametrize("path", ["scenes/stand.ron", "scenes/walk.ron", "scenes/backflip.ron"])
def test_figure_scenes_load_as_figures(assets, path):
    figure = anima.load(assets / path)
    assert isinstance(figure, anima.Figure)
    poses = figure.poses
    assert poses.shape == (len(figure.body_names), 3)
    assert all("/" in name for name in figure.body_names)


def test_optimisation_specs_load(assets):
    opt = anima.Optimisation(assets / "optimisations/walk.ron")
    assert opt.name == "walk-greedy" and opt.budget == 46 and len(opt.names) == 4


def test_gravity_replaces_a_flex3d_scripts(assets):
    # The tablecloth script pushes with its own FORÇA_EXTERNA as well; gravity comes on top.
    fall = {}
    for name, g in [("none", [0.0, 0.0, 0.0]), ("default", None), ("strong", [0.0, -100.0, 0.0])]:
        cloth = anima.load(assets / "flex3d/a2-8-toalha.par", gravity=g)
        y0 = cloth.positions[:, 1].mean()
        cloth.step(20)
        fall[name] = y0 - cloth.positions[:, 1].mean()
    assert 0 < fall["none"] < fall["default"] < fall["strong"]
