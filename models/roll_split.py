r"""Front/rear split of the lateral load transfer: one weak model row.

The three equilibrium rows (eq. 15-17) fix the total load, the pitch moment
and the total roll moment, not how the roll moment is shared between the
axles: the "warp" direction :math:`[1/T_f, -1/T_f, -1/T_r, 1/T_r]` of the
four loads is theirs to leave free. The travel sensors observe it; without
them (IMU-only) the filter needs this row. With :math:`\lambda` the front
share of the lateral load transfer,

.. math:: (1 - \lambda)\,\tfrac{T_f}{2} (F_{FL} - F_{FR})
          - \lambda\,\tfrac{T_r}{2} (F_{RL} - F_{RR}) = 0 ,

i.e. the front axle carries :math:`\lambda` of the roll moment. Its physical
default is the front share of the suspension's roll stiffness,
:math:`\lambda_K = K_f / (K_f + K_r)` with :math:`K = (T/2)\,\partial (F_L -
F_R)/\partial\varphi`, taken from the suspension model's own Jacobian
(springs and anti-roll bars). With the vehicle's ``geometric_transfer``
term on, the roll moment :math:`m f_y h` splits into the part through the
links, :math:`M_{g,a}` per axle from the model's own
:func:`~wheelload.models.suspension.parts.link_loads` (:math:`m f_y (l_r/l)
h_{rc,f}` front), and the elastic rest, shared as :math:`\lambda_K`:

.. math:: \lambda = \frac{M_{g,f} + \lambda_K (m f_y h - M_{g,f} - M_{g,r})}{m f_y h}

The default is :func:`wheelload.models.roll_stiffness.roll_split_default`; the
vehicle file's ``suspension.roll_split_front`` overrides it (a measured
split also holds the unsprung-mass transfer, which the default leaves out).

The row is soft: its noise density is :data:`SPLIT_NOISE_RATIO` times the
roll row's. The row takes no input, so no sensor error enters it; its error
is that of :math:`\lambda` (and the unsprung transfer), proportional to the
roll moment. On the bundled vehicles' plant logs (reference loads, road-frame
rows) its RMS residual is 0.1-0.5 of the roll row's (clean; smaller with
sensor noise, which only the roll row sees): a density ratio of 0.01-0.25,
taken as 0.1. The warp direction it alone observes then has a variance
:math:`\sqrt{q\,r_{split}}/|h|` well below the other rows', where the old
ratio of 4 made it the widest direction of :math:`P` (IMU-only per-wheel
:math:`\sigma` of 395-493 N, 90 % of it from the warp, at an error of
1-100 N).
"""

from __future__ import annotations

import casadi as ca

from wheelload.models.parameters import ModelParameters

SPLIT_NOISE_RATIO = 0.1  # split-row noise density / roll-row noise density


def roll_split_row(p: ModelParameters) -> ca.SX:
    """The 1x4 row :math:`h` of :math:`h x = 0` (module docstring)."""
    share = p.roll_split_front
    half_f, half_r = 0.5 * p.track_front, 0.5 * p.track_rear
    return ca.horzcat((1 - share) * half_f, -(1 - share) * half_f, -share * half_r, share * half_r)


def roll_split_function(name: str = "roll_split") -> ca.Function:
    """``name(p) -> h[1x4]`` as a CasADi Function."""
    p_vector, p = ModelParameters.symbolic()
    return ca.Function(name, [p_vector], [roll_split_row(p)], ["p"], ["h"])
