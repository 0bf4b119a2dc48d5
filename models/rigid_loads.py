r"""Alatorre-style algebraic wheel loads of a rigid body (Siegloff & Choi §IV-B, method B).

.. math::
    F_{FL,FR} = \frac{m}{2L}(l_r f_z - h f_x) \mp \frac{m h \lambda}{T_f} f_y, \quad
    F_{RL,RR} = \frac{m}{2L}(l_f f_z + h f_x) \mp \frac{m h (1 - \lambda)}{T_r} f_y

from the specific force :math:`f` (:math:`\lambda = l_r / L` by default). Used by
the algebraic and quasi-static methods (:mod:`wheelload.models.load_transfer`) and
by the tyre-force term of the pseudo-measurement
(:mod:`wheelload.models.suspension.pseudo_measurement`);
``p`` is a :class:`~wheelload.models.parameters.ModelParameters` (numbers or symbols).
"""

from __future__ import annotations

import casadi as ca


def algebraic_loads(acc, p, front_share=None):
    """Alatorre-style wheel loads from road-frame specific force ``acc`` (module docstring).

    ``front_share`` (e.g. ``p.roll_split_front``) replaces the front axle's
    share :math:`l_r / L` of the lateral load transfer :math:`m h f_y`.
    """
    fx, fy, fz = acc[0], acc[1], acc[2]
    m, h, lf, lr = p.mass, p.cg_height, p.lf, p.lr
    L = lf + lr
    share = lr / L if front_share is None else front_share
    front = m / (2 * L) * (lr * fz - h * fx)
    rear = m / (2 * L) * (lf * fz + h * fx)
    lateral_front = m * h * share / p.track_front * fy
    lateral_rear = m * h * (1 - share) / p.track_rear * fy
    return ca.vertcat(
        front - lateral_front, front + lateral_front, rear - lateral_rear, rear + lateral_rear
    )
