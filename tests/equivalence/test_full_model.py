"""The family methods on the KF's full vehicle model (the default) against independent references.

- Every term switched off in the vehicle file, the full model is the paper's:
  each method that takes the suspension pseudo-measurement or the equilibrium
  from the model gives the paper variant's numbers.
- Method D on the full model is the two-stage KF's own pseudo-measurement,
  evaluated here straight from ``wheelload.models`` (the Functions the KF is
  built from), not through the family's step.
- Method C on the full model meets the KF's equilibrium exactly at rest-travel.
"""

import dataclasses

import numpy as np
import pytest

from wheelload.estimators.family.algebraic import Algebraic
from wheelload.estimators.family.quasi_static import QuasiStatic
from wheelload.estimators.logs.inputs import input_matrix
from wheelload.estimators.logs.signals import read_log
from wheelload.estimators.protocol import SuspensionModel
from wheelload.estimators.registry import build
from wheelload.estimators.types import Signals
from wheelload.models import (
    GRAVITY,
    ModelParameters,
    equilibrium_function,
    gates_function,
    suspension_function,
)
from wheelload.studies.pipeline.example_log import example_log_path

MODEL_METHODS = ["C", "D", "E", "E+C", "F", "ycoo", "umvf", "road-angle"]


@pytest.fixture(scope="module")
def example():
    return read_log(example_log_path()).slice(0, 400)


def without_terms(vehicle):
    off = {field.name: False for field in dataclasses.fields(vehicle.model)}
    return dataclasses.replace(vehicle, model=dataclasses.replace(vehicle.model, **off))


@pytest.mark.parametrize("name", MODEL_METHODS)
def test_full_model_with_every_term_off_is_the_paper_model(name, vehicle, example):
    bare = without_terms(vehicle)
    full = build(name, bare, SuspensionModel.FULL).run(example)
    paper = build(name, bare, SuspensionModel.PAPER).run(example)
    # The same arithmetic reached through the gated Functions: rounding only (1e-9 relative,
    # 1e-6 N absolute for loads near zero differences).
    np.testing.assert_allclose(full.loads, paper.loads, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(full.residual, paper.residual, rtol=1e-9, atol=1e-5)
    np.testing.assert_array_equal(full.flags, paper.flags)


def test_suspension_only_is_the_kf_pseudo_measurement(vehicle):
    example = read_log(example_log_path())  # the whole lane change
    u = input_matrix(example)
    valid = np.isfinite(u).astype(float)
    p = ModelParameters.from_vehicle(vehicle).vector()
    n = u.shape[1]
    gates = np.asarray(gates_function().map(n)(valid, p)[0])
    z = np.asarray(suspension_function().map(n)(np.nan_to_num(u), gates, p)).T
    loads = build("D", vehicle).run(example).loads
    # Same Functions, evaluated by CasADi here and in the generated C there: 1e-9 relative.
    np.testing.assert_allclose(loads, z, rtol=1e-9)
    # The model terms matter on this log (links, tyre forces, unsprung inertia): more than
    # 50 N RMS against the paper's eq. 9 alone.
    paper = build("D", vehicle, SuspensionModel.PAPER).run(example).loads
    assert np.sqrt(np.mean((loads - paper) ** 2)) > 50.0


def constant_log(acc, vx, n=200) -> Signals:
    return Signals(
        t=0.01 * np.arange(1, n + 1), vx=np.full(n, vx), acc=np.tile(acc, (n, 1)),
        d=np.zeros((n, 4)), v=np.zeros((n, 4)),
    )  # fmt: skip


@pytest.mark.parametrize("acc", [(3.0, -5.0, GRAVITY), (-7.0, 8.0, 10.5)])
def test_quasi_static_meets_the_kf_equilibrium(vehicle, acc):
    signals = constant_log(acc, vx=40.0)
    estimate = QuasiStatic(vehicle).run(signals)
    u = input_matrix(signals)[:, -1]
    p = ModelParameters.from_vehicle(vehicle).vector()
    gates = gates_function()(np.isfinite(u).astype(float), p)[0]
    A, b = (np.asarray(m) for m in equilibrium_function()(np.nan_to_num(u), gates, p))
    # Exact equilibrium of the rigid body on its suspension: rounding (1e-6 N, N m).
    np.testing.assert_allclose(A @ estimate.loads[-1], b.ravel(), atol=1e-6)
    # The links carry part of the lateral transfer: the left-right split differs from
    # the paper's spring-and-bar split (by tens of newtons at these accelerations).
    paper = QuasiStatic(vehicle, suspension=SuspensionModel.PAPER).run(signals).loads[-1]
    assert np.max(np.abs(estimate.loads[-1] - paper)) > 10.0


def test_algebraic_full_model_is_the_split_of_the_kf_equilibrium(vehicle):
    # Level road, body at its static attitude, no speed: the road-frame rotation is the
    # identity and the rows are m f_z, -m h f_x, -m h f_y; by hand (Alatorre, static split):
    # F_FL,FR = m/(2L) (l_r f_z - h f_x) -/+ m h l_r f_y / (L T_f), the rear likewise.
    fx, fy, fz = 2.0, -3.0, GRAVITY
    estimate = Algebraic(without_terms(vehicle)).run(constant_log((fx, fy, fz), vx=0.0))
    p = ModelParameters.from_vehicle(vehicle)
    L = p.lf + p.lr
    front = p.mass / (2 * L) * (p.lr * fz - p.cg_height * fx)
    rear = p.mass / (2 * L) * (p.lf * fz + p.cg_height * fx)
    lat_f = p.mass * p.cg_height * p.lr / (L * p.track_front) * fy
    lat_r = p.mass * p.cg_height * p.lf / (L * p.track_rear) * fy
    expected = [front - lat_f, front + lat_f, rear - lat_r, rear + lat_r]
    np.testing.assert_allclose(estimate.loads[-1], expected, rtol=1e-12)
