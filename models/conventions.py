r"""Conventions every model, estimator and study shares (DESIGN.md, "Conventions").

- Wheel order FL, FR, RL, RR: :data:`WHEELS`, the order of every 4-vector; axle order
  front, rear: :data:`AXLES`, and the vehicle file's tables of the two axles'
  suspensions: :data:`SUSPENSION_TABLES`.
- Body axes ISO 8855: x forward, y left, z up; the accelerometer gives specific
  force, gravity included (:math:`a_z \approx +g` at rest on level ground).
- SI units; :data:`GRAVITY` is standard gravity (ISO 80000-3).

Example
-------
>>> WHEELS.index("rl")
2
"""

WHEELS = ("fl", "fr", "rl", "rr")
GRAVITY = 9.80665  # m/s^2, standard gravity
AXLES = ("front", "rear")
SUSPENSION_TABLES = tuple(f"suspension.{axle}" for axle in AXLES)
