"""``wheelload study`` experiments in --quick mode: the runner, its cache and Dask, end to end."""

import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from wheelload.estimators.logs.signals import signals_from_frame
from wheelload.estimators.registry import build, methods
from wheelload.models import example_vehicle_path
from wheelload.studies.cli import main
from wheelload.studies.drive.scenario_runner import run_scenario
from wheelload.studies.experiments.catalog import run_study
from wheelload.studies.experiments.mismatch import mismatch_variants
from wheelload.studies.experiments.runs.cache import ResultCache, cache_key
from wheelload.studies.experiments.runs.common import ISO_DLC_WINDOW, truth_spec
from wheelload.studies.experiments.runs.context import Context, Outputs, Settings
from wheelload.studies.experiments.runs.runner import Runner
from wheelload.studies.experiments.runs.units import TRUTH
from wheelload.studies.experiments.runs.vehicle_variants import Edit, Variant, value
from wheelload.studies.experiments.vehicle_file_ablation import ablation_variants, model_switches
from wheelload.studies.metrics import wheel_metrics

pytestmark = pytest.mark.heavy(14)  # seconds (tests/conftest.py)


def _settings() -> Settings:
    path = example_vehicle_path()
    return Settings(vehicle_path=path, vehicles_folder=path.parent, quick=True)


def test_iso_dlc_quick_table_matches_a_direct_run_and_rerun_hits_the_cache(tmp_path, capsys):
    out = tmp_path / "iso"
    code = main(["study", "iso-dlc", "--quick", "--out", str(out), "--workers", "2",
                 "--no-progress"])  # fmt: skip
    assert code == 0  # on 2 local processes, the default
    count = len(methods())
    assert f"{count + 1} jobs computed, 0 from the cache" in capsys.readouterr().out
    for name in ("iso-dlc.md", "iso-dlc_loads.png", "iso-dlc_metrics.png"):
        assert (out / name).stat().st_size > 1000
    table = pd.read_csv(out / "iso-dlc_table.csv", index_col=[0, 1])
    # projection-mp and projection-ls are identical on the ISO DLC (P ∝ I before the
    # projection, every travel sensor present): one row, named for both, with a note.
    assert len(table) == 4 * (count - 1)
    assert ("RMSE [N]", "projection-mp = projection-ls") in table.index
    assert "*Note:* projection-mp = projection-ls: identical" in (out / "iso-dlc.md").read_text()
    # Independent check: the scenario runner's own log (noise 1, seed 0), the KF from the
    # registry, the paper's metrics over 5-12 s; equal to the CSV's 3 decimals.
    log = run_scenario("iso-dlc", example_vehicle_path()).log
    signals = signals_from_frame(log)
    loads = build("kf", _vehicle()).run(signals).loads
    mask = (signals.t >= ISO_DLC_WINDOW[0]) & (signals.t <= ISO_DLC_WINDOW[1])
    direct = wheel_metrics(loads[mask], signals.reference[mask])
    assert np.allclose(table.loc[("RMSE [N]", "kf"), ["FL", "FR", "RL", "RR", "POOLED"]],
                       direct["RMSE"], atol=1e-3)  # fmt: skip
    assert np.allclose(table.loc[("Max [N]", "kf"), "POOLED"], direct.loc["pooled", "Max"],
                       atol=1e-3)  # fmt: skip
    # A rerun (in this process) recomputes nothing (the runner's accounting), and refuses
    # to overwrite an output without --force.
    with pytest.raises(ValueError, match="--force"):
        main_outputs = Outputs(folder=out)
        main_outputs.path("iso-dlc.md")
    runner = Runner(cache=ResultCache(folder=out / ".cache"), workers=1, progress=False)
    context = Context(settings=_settings(), runner=runner, outputs=Outputs(folder=out, force=True))
    run_study("iso-dlc", context)
    assert (runner.computed, runner.cached) == (0, count + 1)


def _vehicle():
    from wheelload.models import load_vehicle

    return load_vehicle(example_vehicle_path())


def test_ablation_quick_on_a_local_dask_cluster(tmp_path):
    distributed = pytest.importorskip("distributed")
    cache = tmp_path / "cache"
    with distributed.LocalCluster(n_workers=1, processes=False, threads_per_worker=2,
                                  dashboard_address=":0") as cluster:  # fmt: skip
        runner = Runner(cache=ResultCache(folder=cache), dask_address=cluster.scheduler_address,
                        progress=False)  # fmt: skip
        outputs = Outputs(folder=tmp_path)
        with runner:
            run_study("ablation", Context(settings=_settings(), runner=runner, outputs=outputs))
    cases = len(ablation_variants(_settings().vehicle_text))
    # The trials find the plant run that the study simulated first in the cache.
    assert (runner.computed, runner.cached) == (1 + cases, 1)
    table = pd.read_csv(tmp_path / "ablation_table.csv", index_col=0)
    assert list(table.index[:5]) == ["baseline", "no aero", "no ARB", "symmetric damper",
                                     "no constraints"]  # fmt: skip
    assert np.isfinite(table.to_numpy()).all()
    # The baseline row equals the KF run here on the truth the cluster simulated and cached,
    # measured with seed 0 at s = 1 (the sensor model's own stream).
    truth = ResultCache(folder=cache).load(cache_key(TRUTH, truth_spec(_context(), "nordschleife")))
    from wheelload.studies.drive.sensors import measure

    rng = np.random.default_rng(np.random.SeedSequence([0, 1]))
    signals = signals_from_frame(measure(truth, 1.0, rng), wiring_checks=False)  # as the study
    direct = wheel_metrics(build("kf", _vehicle()).run(signals).loads, signals.reference)
    assert np.isclose(table.loc["baseline", "RMSE [N]"], direct.loc["pooled", "RMSE"], atol=1e-3)
    # Dropping the equilibrium update must change the estimate.
    assert table.loc["no constraints", "RMSE [N]"] != table.loc["baseline", "RMSE [N]"]


def _context() -> Context:
    runner = Runner(cache=ResultCache(folder=Path(".")), progress=False)
    return Context(settings=_settings(), runner=runner, outputs=Outputs(folder=Path(".")))


def test_vehicle_variants_edit_only_their_keys():
    text = example_vehicle_path().read_text()
    variant = Variant(label="x", edits=(
        Edit(table="suspension.rear", key="arb_rate", value=0.0),
        Edit(table="filter", key="constraint_noise_density", value=(1.0, 2.0, 3.0)),
    ))  # fmt: skip
    edited = variant.apply(text)
    assert value(edited, "suspension.rear", "arb_rate") == 0.0
    assert value(edited, "suspension.front", "arb_rate") == value(text, "suspension.front",
                                                                   "arb_rate")  # fmt: skip
    assert value(edited, "filter", "constraint_noise_density") == (1.0, 2.0, 3.0)
    assert len(edited.splitlines()) == len(text.splitlines())
    with pytest.raises(ValueError, match="no key 'aero.nothing'"):
        Variant(label="bad", edits=(Edit(table="aero", key="nothing", value=1.0),)).apply(text)
    # Mass: sprung x 1.2 and the total follows; every mismatch case is a valid vehicle.
    cases = mismatch_variants(text)
    assert len(cases) == 11
    heavy = next(v for v in cases if v.label == "mass +20 %").apply(text)
    assert np.isclose(value(heavy, "mass", "sprung"), 1.2 * value(text, "mass", "sprung"))
    # The model-fidelity switches become ablation cases: each of the [model] section flipped.
    switches = model_switches(text)
    assert [v.label for v in switches] == [
        f"model {key} off"
        for key in ("road_frame", "body_inertia", "geometric_transfer", "stops",
                    "unsprung_inertia", "imu_lever_arm")
    ]  # fmt: skip
    assert tomllib.loads(switches[0].apply(text))["model"]["road_frame"] is False
    without = text.replace("[model]", "[switches]")  # no [model] section: no cases
    assert model_switches(without) == []


def test_cache_key_follows_the_vehicle_bytes():
    text = example_vehicle_path().read_text()
    spec = truth_spec(_context(), "iso-dlc")
    other = truth_spec(_context(), "iso-dlc", vehicle_text=text + "\n# comment\n")
    assert cache_key(TRUTH, spec) == cache_key(TRUTH, truth_spec(_context(), "iso-dlc"))
    assert cache_key(TRUTH, spec) != cache_key(TRUTH, other)
