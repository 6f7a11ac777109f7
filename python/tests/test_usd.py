"""USD out: every stage anima writes passes USD's own validators (`pxr.UsdValidation`, from Pixar's
`usd-core`), declares its axes and units, and holds the run's frames: the points at frame k's time code
are the positions of the run's frame k (as f32, turned to y up)."""

from pathlib import Path

import anima
import pytest
from pxr import Usd, UsdGeom, UsdValidation


def validation_errors(path: Path) -> list[str]:
    registry = UsdValidation.ValidationRegistry()
    context = UsdValidation.ValidationContext(registry.GetOrLoadAllValidators())
    stage = Usd.Stage.Open(str(path))
    return [f"{e.GetName()}: {e.GetMessage()}" for e in context.Validate(stage)]


def read_obj(path: Path) -> list[tuple[float, float, float]]:
    return [
        tuple(float(v) for v in line.split()[1:4])
        for line in path.read_text().splitlines()
        if line.startswith("v ")
    ]


def test_a_sheet_run_as_usd_is_valid_and_holds_its_frames(assets, tmp_path):
    summary = anima.run(assets / "scenes/standard-sheet-32.ron", tmp_path, duration=0.2, export="usd")
    path = tmp_path / "animation.usda"
    assert validation_errors(path) == []
    stage = Usd.Stage.Open(str(path))
    assert UsdGeom.GetStageUpAxis(stage) == "Y" and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetTimeCodesPerSecond() == 1000.0
    sheet = UsdGeom.Mesh(stage.GetPrimAtPath("/anima/sheet"))
    times = sheet.GetPointsAttr().GetTimeSamples()
    frames = summary["frames"]
    assert len(times) == frames + 1, "frame 0 and every frame of the run"
    assert times[-1] == pytest.approx(1000.0 * summary["simulated_seconds"], rel=1e-6)
    for k in (1, frames):
        run = read_obj(tmp_path / f"sheet_{k}.obj")
        usd = sheet.GetPointsAttr().Get(times[k])
        assert len(usd) == len(run)
        # The standard sheet is z up: (x, y, z) is (x, z, -y) in the stage's y-up axes.
        for (x, y, z), p in zip(run, usd):
            assert tuple(p) == pytest.approx((x, z, -y), rel=1e-6, abs=1e-7)


def test_remeshed_cloth_and_figures_as_usd_are_valid(assets, tmp_path):
    anima.run(assets / "oliveira/test-1-bunny-adaptive.ron", tmp_path / "cloth", duration=0.3, export="usd")
    path = tmp_path / "cloth/animation.usda"
    assert validation_errors(path) == []
    stage = Usd.Stage.Open(str(path))
    cloth = UsdGeom.Mesh(stage.GetPrimAtPath("/anima/cloth"))
    assert len(cloth.GetFaceVertexIndicesAttr().GetTimeSamples()) > 1, "the topology is time-sampled"
    assert UsdGeom.Mesh(stage.GetPrimAtPath("/anima/bunny")).GetPointsAttr().Get() is not None

    anima.run(assets / "scenes/walk.ron", tmp_path / "walk", duration=1.0, export="usd")
    path = tmp_path / "walk/animation.usda"
    assert validation_errors(path) == []
    stage = Usd.Stage.Open(str(path))
    links = [p for p in stage.Traverse() if p.IsA(UsdGeom.Xform) and p.GetParent().GetPath() != "/"]
    assert len(links) > 5
    moving = [p for p in links if len(UsdGeom.Xformable(p).GetOrderedXformOps()) == 2]
    assert moving and all(len(UsdGeom.Xformable(p).GetOrderedXformOps()[0].GetTimeSamples()) > 2 for p in moving)
