"""The filter step's inputs and outputs by name: what its callers read of it.

Kept apart from :mod:`wheelload.estimators.kf.step` (which builds the step from the
symbolic models) so that a warm estimate, which runs the stored step as compiled C,
imports none of the models.
"""

#: The step Function's name (and its C symbol).
STEP_NAME = "wheelload_kf_step"
STEP_INPUT_NAMES = ["x", "P", "m", "u", "u_valid", "dt", "p", "tuning"]
STEP_OUTPUT_NAMES = [
    "x_next", "P_next", "m_next", "std", "residual", "used", "z", "innovation",
    "innovation_variance", "status", "fault_statistic", "fault", "mass_properties",
    "mass_properties_std",
]  # fmt: skip
#: The step's carried state: x, P and the monitor m.
N_CARRIED = 3
#: The seven update rows in update order (innovation outputs).
UPDATE_ROWS = (
    "suspension_fl", "suspension_fr", "suspension_rl", "suspension_rr",
    "vertical", "pitch", "roll",
)  # fmt: skip
