"""The plant scenarios by name, in order: what ``--scenarios`` and ``--identify-on`` offer.

A table of names only, so that a command's ``--help`` lists them without building the plant;
:data:`~wheelload.studies.drive.scenarios.SCENARIOS` checks itself against it on import.
"""

SCENARIO_NAMES = (
    "iso-dlc",
    "brake-in-turn",
    "accel-in-turn",
    "bounce-sweep",
    "slope-20",
    "chicane-bank-30",
    "chicane-incline-20",
    "wheel-lift",
    "standstill",
    "stop-and-go",
    "hockenheim",
    "nordschleife",
)
#: The laps: whole tracks, minutes long.
LAPS = ("hockenheim", "nordschleife")
#: Every scenario but the laps: the manoeuvres of seconds to a minute.
MANOEUVRES = tuple(name for name in SCENARIO_NAMES if name not in LAPS)
