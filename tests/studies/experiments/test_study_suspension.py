"""``wheelload study ... --suspension full|paper``: the model reaches the family methods and
the report names it."""

import pandas as pd

from wheelload.estimators.protocol import SuspensionModel
from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main
from wheelload.studies.experiments import catalog, cheon_structural
from wheelload.studies.experiments.runs.cache import ResultCache
from wheelload.studies.experiments.runs.context import Context, Outputs, Settings
from wheelload.studies.experiments.runs.runner import Runner


def _study(tmp_path, model: str | None) -> tuple[pd.DataFrame, str]:
    out = tmp_path / (model or "default")
    extra = [] if model is None else ["--suspension", model]
    code = main(["study", "cheon-structural", "--quick", "--out", str(out), "--workers", "1",
                 "--no-progress", "--cache", str(tmp_path / "cache"), *extra])  # fmt: skip
    assert code == 0
    table = pd.read_csv(out / "cheon-structural_table.csv", index_col=0)
    return table, (out / "cheon-structural.md").read_text()


def test_study_suspension_reaches_the_family_methods_only(tmp_path, capsys):
    paper, paper_md = _study(tmp_path, "paper")
    full, full_md = _study(tmp_path, "full")
    default, default_md = _study(tmp_path, None)
    # E and E+C take the model: their errors differ by more than rounding (the paper's bare
    # model leaves out the vehicle file's link, stop and unsprung terms).
    for name in ("E", "E+C"):
        assert abs(paper.loc[name, "RMSE [N]"] - full.loc[name, "RMSE [N]"]) > 1.0
    # the KF has no model choice: the same numbers
    assert paper.loc["kf"].equals(full.loc["kf"])
    pd.testing.assert_frame_equal(default, full)  # full is the default
    assert "Vehicle model of the family methods: **paper** (`--suspension paper`)" in paper_md
    assert "Vehicle model of the family methods: **full** (`--suspension full`)" in full_md
    assert "**full**" in default_md
    # plant run and KF trial from the cache on the second run, everything on the third
    runs = capsys.readouterr().out.splitlines()
    assert "2 jobs computed, 2 from the cache" in runs[1]
    assert "0 jobs computed, 4 from the cache" in runs[2]


def test_report_names_the_model(tmp_path, monkeypatch):
    # `all` with one cheap study and no shared plant runs: REPORT.md's model line
    monkeypatch.setattr(catalog, "STUDIES", {"cheon-structural": cheon_structural.run})
    monkeypatch.setattr(catalog, "plant_runs", lambda context: [])
    path = example_vehicle_path()
    settings = Settings(vehicle_path=path, vehicles_folder=path.parent, quick=True,
                        suspension=SuspensionModel.PAPER)  # fmt: skip
    runner = Runner(cache=ResultCache(folder=tmp_path / "cache"), workers=1, progress=False)
    with runner:
        catalog.run_study("all", Context(settings=settings, runner=runner,
                                         outputs=Outputs(folder=tmp_path)))  # fmt: skip
    report = (tmp_path / "REPORT.md").read_text()
    assert "Vehicle model of the family methods: **paper**" in report
    assert "## Structural comparison" in report
