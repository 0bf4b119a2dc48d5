"""What every study is given: its settings, the shared runner and a guarded output folder.

Outputs never replace an existing file without ``force``; each is written to
a temporary file in the output folder and renamed (removed on an error, Ctrl-C
or SIGTERM; a killed run's is removed when the folder is written next:
:mod:`wheelload.models.runtime.temporaries`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from wheelload.estimators import DEFAULT_MODEL, SuspensionModel
from wheelload.models.runtime.temporaries import replacing
from wheelload.studies.experiments.runs.choices import SHORT_WORDS, EstimatorModel
from wheelload.studies.experiments.runs.runner import Runner

QUICK_SHORTEN = 0.01  # share of a lap driven in --quick mode
QUICK_TRIALS = 2  # Monte Carlo trials per noise scale in --quick mode


@dataclass(frozen=True, kw_only=True)
class Settings:
    """A study's inputs: the plant's (and the estimators') vehicle file, the mode, the
    estimators' vehicle model (:class:`~wheelload.studies.experiments.runs.estimator_model.
    EstimatorModel`: the file's or the paper's) and that of the family methods
    (:class:`~wheelload.estimators.SuspensionModel`)."""

    vehicle_path: Path
    vehicles_folder: Path  # every *.toml here is a bundled vehicle (study `vehicles`)
    quick: bool = False
    suspension: SuspensionModel = DEFAULT_MODEL
    model: EstimatorModel = EstimatorModel.FULL

    @property
    def vehicle_text(self) -> str:
        return Path(self.vehicle_path).read_text(encoding="utf-8")

    @property
    def vehicle_name(self) -> str:
        """The vehicle file's ``name`` (the car every table and figure names)."""
        import tomllib

        return str(tomllib.loads(self.vehicle_text).get("name", Path(self.vehicle_path).stem))

    @property
    def shorten(self) -> float:
        return QUICK_SHORTEN if self.quick else 1.0


def model_caption(settings: Settings) -> str:
    """The line under a table naming the vehicle models it is on (``--model``, ``--suspension``)."""
    model, suspension = settings.model.value, settings.suspension.value
    return (
        f"*Vehicle:* **{settings.vehicle_name}** (`{Path(settings.vehicle_path).name}`). "
        f"*Model:* kf, projection and mhe on the **{model}** model (`--model {model}`: "
        f"{SHORT_WORDS[settings.model]}); the family methods on `--suspension {suspension}`."
    )


@dataclass(kw_only=True)
class Outputs:
    """The output folder; remembers what it wrote."""

    folder: Path
    force: bool = False
    written: list[Path] = field(default_factory=list)

    def path(self, name: str) -> Path:
        """The target path of ``name``, refused if it exists and ``force`` is not given."""
        path = Path(self.folder) / name
        if path.exists() and not self.force:
            raise ValueError(f"{path}: exists; give --force to replace it")
        return path

    def write_text(self, name: str, text: str) -> Path:
        path = self.path(name)
        self._replace(path, text.encode("utf-8"))
        return path

    def save_figure(self, figure, name: str) -> Path:
        path = self.path(name)
        with replacing(path) as temporary:
            figure.savefig(temporary, dpi=110)
        self.written.append(path)
        return path

    def _replace(self, path: Path, data: bytes) -> None:
        with replacing(path) as temporary:
            temporary.write_bytes(data)
        self.written.append(path)


@dataclass(frozen=True, kw_only=True)
class Context:
    settings: Settings
    runner: Runner
    outputs: Outputs
