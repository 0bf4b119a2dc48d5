"""The many-logs library is built once per model structure; the vehicle's values reach it.

- The structure key ignores what the C does not depend on (a comment, +1 kg, a new spring
  rate, the vehicle's name) and changes with what it does (a model term switched, the
  precision).
- Builds are counted through the build folder's own records (``<library>.sha256``, written
  at each build): an edit of the file's values runs through the library built before (no
  record added or rewritten), while the loads follow the edit exactly as the single-log
  filter's do (a +20 % front spring rate, to 1e-12 relative as ``test_batched.py``
  states: the fast build contracts FMAs where the compiled ``run`` rounds twice).
- A model term switched off runs through another library (its own record).

Both run in a build folder of their own, with the library's flags at ``-O0`` instead of
``-O3``: what they check is which library a file meets and the loads it gives, not the
optimiser (``test_batched.py`` checks the fast build itself). The real compiler builds
every library here, in seconds instead of the fast build's minute.
"""

import dataclasses
import re

import numpy as np
import pytest
from c_parity import assert_c_equals_python

from wheelload.estimators.codegen import batched
from wheelload.estimators.codegen.batched import OPTIONS, batch_library, run_batched
from wheelload.estimators.codegen.structure import structure_key
from wheelload.estimators.kf.two_stage import TwoStageKF
from wheelload.models import example_vehicle_path, load_vehicle
from wheelload.models.runtime.build_folder import build_folder

pytestmark = pytest.mark.heavy(40)  # three -O0 builds of the library


@pytest.fixture
def debug_builds(tmp_path, monkeypatch):
    """The library's compiles at -O0 (the fast flags' -O3 swapped out; the loads stay
    C = Python to 1e-12 relative), their structure records in the test's own folder: the
    shared build folder keeps the -O0 builds under their own names (a build is named by its
    text and flags) and no record of the fast build is replaced."""
    unoptimised = lambda flags: tuple("-O0" if flag == "-O3" else flag for flag in flags)  # noqa: E731
    records = tmp_path / "records"
    records.mkdir()
    monkeypatch.setattr(batched, "KERNEL_FLAGS", unoptimised(batched.KERNEL_FLAGS))
    monkeypatch.setattr(batched, "SHARED_FLAGS", unoptimised(batched.SHARED_FLAGS))
    monkeypatch.setattr(
        batched, "structure_record", lambda key: records / f"{batched.PREFIX}_{key[:32]}.structure"
    )
    batched._library.cache_clear()
    yield records
    batched._library.cache_clear()  # no -O0 build is left for the other tests


def _edited(tmp_path, name, *edits):
    """The example vehicle file with ``(pattern, replacement)`` edits (each must match)."""
    text = example_vehicle_path().read_text()
    for pattern, replacement in edits:
        text, count = re.subn(pattern, replacement, text, count=1, flags=re.MULTILINE)
        assert count == 1, pattern
    path = tmp_path / name
    path.write_text(text)
    return path


SPRING = (r"^spring_rate = 60000.0", "spring_rate = 72000.0")  # front, +20 %
KILOGRAM = (r"^sprung = 1424.2", "sprung = 1425.2"), (r"^total = 1613.2", "total = 1614.2")
COMMENT = (r"\Z", "\n# tuned on the test track\n")
NO_STOPS = (r"^stops = true", "stops = false")  # bump and rebound stops off


def _records(structures):
    """The structure records in ``structures`` and the build records of the libraries they
    name: name -> (inode, mtime)."""
    paths = list(structures.glob("*.structure"))
    for record in list(paths):
        paths += [build_folder() / f"{name}.sha256" for name in record.read_text().split()]
    return {path.name: (path.stat().st_ino, path.stat().st_mtime_ns) for path in paths}


def test_the_structure_key_ignores_values_and_follows_switches(tmp_path):
    step = TwoStageKF(load_vehicle(example_vehicle_path())).step_function
    key = lambda path, options=OPTIONS: structure_key(step, load_vehicle(path), options)  # noqa: E731
    base = key(example_vehicle_path())
    for name, edits in {
        "comment": (COMMENT,),
        "kilogram": KILOGRAM,
        "spring": (SPRING,),
        "renamed": ((r'^name = "sports_car"', 'name = "my car"'),),
    }.items():
        assert key(_edited(tmp_path, f"{name}.toml", *edits)) == base, name
    assert key(_edited(tmp_path, "stops.toml", NO_STOPS)) != base
    from wheelload.estimators.kernels.c_emitter import Precision

    single = dataclasses.replace(OPTIONS, precision=Precision.FLOAT)
    assert key(example_vehicle_path(), single) != base


def test_a_value_edit_reuses_the_library_and_reaches_the_loads(tmp_path, plant_log, debug_builds):
    logs = [plant_log("iso-dlc").slice(0, 900), plant_log("iso-dlc").slice(300, 700)]
    base_kf = TwoStageKF(load_vehicle(example_vehicle_path()))
    base = run_batched(base_kf, example_vehicle_path(), logs)  # built here or before
    library = batch_library(base_kf.step_function, example_vehicle_path()).path
    records = _records(debug_builds)
    assert library.name + ".sha256" in records
    edited = _edited(tmp_path, "edited.toml", COMMENT, *KILOGRAM, SPRING)
    kf = TwoStageKF(load_vehicle(edited))
    assert kf.vehicle.suspension.front.spring_rate == 72000.0
    batched = run_batched(kf, edited, logs)
    assert batch_library(kf.step_function, edited).path == library
    assert _records(debug_builds) == records  # no build: no record added or rewritten
    for log, estimate, before in zip(logs, batched, base, strict=True):
        expected, unedited = kf.run(log), base_kf.run(log)
        scale = np.abs(expected.loads).max()
        assert_c_equals_python(estimate.loads, expected.loads, rtol=1e-12, atol=1e-12 * scale)
        # the edit moves the batched loads as it moves the single-log filter's
        np.testing.assert_allclose(
            estimate.loads - before.loads,
            expected.loads - unedited.loads,
            rtol=0,
            atol=2e-12 * scale,
        )
        assert np.abs(expected.loads - unedited.loads).max() > 1.0  # N: the edit matters


def test_a_model_term_switched_off_builds_another_library(tmp_path, plant_log, debug_builds):
    log = plant_log("iso-dlc").slice(0, 600)
    base_kf = TwoStageKF(load_vehicle(example_vehicle_path()))
    base = batch_library(base_kf.step_function, example_vehicle_path()).path
    switched = _edited(tmp_path, "no_stops.toml", NO_STOPS)
    kf = TwoStageKF(load_vehicle(switched))
    (estimate,) = run_batched(kf, switched, [log])
    library = batch_library(kf.step_function, switched).path
    assert library != base
    assert len(list(debug_builds.glob("*.structure"))) == 2  # a record of its own
    assert library.name + ".sha256" in _records(debug_builds)  # naming its own build
    expected = kf.run(log)
    scale = np.abs(expected.loads).max()
    assert_c_equals_python(estimate.loads, expected.loads, rtol=1e-12, atol=1e-12 * scale)
