"""The light name tables ``--help`` lists equal the registries the studies run from."""

from wheelload.estimators import protocol, suspension_choice
from wheelload.studies.drive import scenario_names, scenarios
from wheelload.studies.experiments import catalog, identification_study, mhe_vs_kf
from wheelload.studies.experiments.faults import sensor_faults
from wheelload.studies.experiments.runs import choices, estimator_model


def test_the_experiment_names_are_the_catalogs():
    assert choices.EXPERIMENT_NAMES == (*catalog.STUDIES, "all")


def test_the_scenario_names_are_the_plants_scenarios_in_order():
    assert scenario_names.SCENARIO_NAMES == tuple(scenarios.SCENARIOS)


def test_the_studies_default_scenarios_exist():
    named = set(scenarios.SCENARIOS)
    assert sorted(set(choices.STUDY_SCENARIOS) - named) == []
    assert choices.IDENTIFY_ON in named
    assert identification_study.StudySettings().identify_on == choices.IDENTIFY_ON


def test_the_enums_are_defined_once():
    """The heavy modules hand out the light modules' enums themselves, not copies."""
    assert sensor_faults.Fault is mhe_vs_kf.Fault is choices.Fault
    assert estimator_model.EstimatorModel is choices.EstimatorModel
    assert protocol.SuspensionModel is suspension_choice.SuspensionModel
    assert protocol.DEFAULT_MODEL is suspension_choice.DEFAULT_MODEL
    assert mhe_vs_kf.HORIZONS is choices.HORIZONS
