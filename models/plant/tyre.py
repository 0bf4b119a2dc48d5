r"""Combined-slip tyre forces: Magic Formula with normalised-slip combination.

Pure slip (Pacejka, *Tire and Vehicle Dynamics*, 3rd ed., eq. 4.49):

.. math:: F = D \sin\bigl(C \arctan(B x - E (B x - \arctan B x))\bigr), \quad
          D = \mu_0 (1 + p_{D2}\, df_z) F_z, \quad B = K / (C D)

with :math:`K_x = p_{Kx1} F_z` and
:math:`K_y = p_{Ky1} F_{z0} \sin(2 \arctan(F_z / (p_{Ky2} F_{z0})))`.
Combined slip scales each slip by its pure-slip peak,
:math:`\rho = \sqrt{(\kappa/\kappa_p)^2 + (\alpha/\alpha_p)^2}`, and gives
:math:`F_x = F_{x0}(\rho \kappa_p)\, (\kappa/\kappa_p)/\rho`,
:math:`F_y = F_{y0}(\rho \alpha_p)\, (\alpha/\alpha_p)/\rho`: a friction
ellipse at the limit and the pure-slip curves when the other slip is zero.
"""

from __future__ import annotations

import math

import casadi as ca

from wheelload.models.vehicle.plant_section import TyreForces


def peak_input(shape: float, curvature: float) -> float:
    r"""The argument :math:`X = B x` at which the magic formula peaks.

    Solves :math:`X - E (X - \arctan X) = \tan(\pi / (2 C))` by bisection.
    """
    target = math.tan(math.pi / (2.0 * shape))
    low, high = 0.0, 1.0e3
    for _ in range(200):
        mid = 0.5 * (low + high)
        if mid - curvature * (mid - math.atan(mid)) < target:
            low = mid
        else:
            high = mid
    return 0.5 * (low + high)


def magic_formula(x, b, c, d, e):
    """Pure-slip magic formula :math:`D \\sin(C \\arctan(Bx - E(Bx - \\arctan Bx)))`."""
    bx = b * x
    return d * ca.sin(c * ca.atan(bx - e * (bx - ca.atan(bx))))


def tyre_forces(kappa, tan_alpha, fz, nominal_load, tyre: TyreForces):
    """Longitudinal and lateral tyre force [N] from slip ratio, tan(slip angle), load.

    ``nominal_load`` is :math:`F_{z0}` of this tyre; forces vanish at ``fz = 0``.
    """
    dfz = (fz - nominal_load) / nominal_load
    scale = 1.0 + tyre.friction_load_sensitivity * dfz
    fz_safe = ca.fmax(fz, 1.0)
    # Longitudinal: B_x = K_x / (C_x D_x) = p_Kx1 / (C_x mu_x), independent of F_z.
    mu_x = tyre.friction_x * scale
    b_x = tyre.slip_stiffness_x / (tyre.shape_x * mu_x)
    # Lateral: B_y = K_y / (C_y mu_y F_z), finite as F_z -> 0 through fz_safe.
    mu_y = tyre.friction_y * scale
    k_y = (
        tyre.cornering_stiffness_y
        * nominal_load
        * ca.sin(2.0 * ca.atan(fz_safe / (tyre.cornering_load_y * nominal_load)))
    )
    b_y = k_y / (tyre.shape_y * mu_y * fz_safe)
    kappa_peak = peak_input(tyre.shape_x, tyre.curvature_x) / b_x
    alpha_peak = peak_input(tyre.shape_y, tyre.curvature_y) / b_y
    sx = kappa / kappa_peak
    sy = tan_alpha / alpha_peak
    rho = ca.sqrt(sx**2 + sy**2 + 1e-12)
    fx0 = magic_formula(rho * kappa_peak, b_x, tyre.shape_x, mu_x * fz, tyre.curvature_x)
    fy0 = magic_formula(rho * alpha_peak, b_y, tyre.shape_y, mu_y * fz, tyre.curvature_y)
    return fx0 * sx / rho, fy0 * sy / rho
