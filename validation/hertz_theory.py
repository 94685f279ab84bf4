"""Hertz's solution for two elastic bodies with curved surfaces pressed together: the one copy of
the formulas every validation suite compares with.

A sphere (3D) or a cylinder (2D, plane strain, per unit length) of effective radius ``R`` on a
flat, with the contact modulus ``E*`` of the pair, ``1 / E* = (1 - nu1^2) / E1 + (1 - nu2^2) / E2``
(a rigid body contributes nothing). At the contact force ``P``:

- 3D: contact radius ``a = (3 P R / (4 E*))^(1/3)``, peak pressure ``p0 = 3 P / (2 pi a^2)``,
  approach of distant points ``delta = a^2 / R``, i.e. ``P = 4/3 E* R^(1/2) delta^(3/2)``;
- 2D: half-width ``a = (4 P R / (pi E*))^(1/2)``, peak pressure ``p0 = 2 P / (pi a)``; the approach
  has no closed form (it depends on where the bodies are held).

The pressure is ``p0 sqrt(1 - r^2 / a^2)`` inside the contact zone in both cases.
"""

import math


def contact_modulus(bodies: list[tuple[float, float]]) -> float:
    """``E*`` of the bodies' ``(E, nu)`` pairs (one pair: the other body rigid)."""
    return 1.0 / sum((1.0 - nu**2) / e for e, nu in bodies)


def contact(force: float, radius: float, e_star: float, dim: int) -> dict:
    """The contact radius (3D) or half-width (2D) ``a`` and peak pressure ``p0`` at the force ``P``;
    in 3D also the approach ``delta``."""
    if dim == 3:
        a = (3 * force * radius / (4 * e_star)) ** (1 / 3)
        return {"a": a, "p0": 3 * force / (2 * math.pi * a**2), "delta": a**2 / radius}
    a = math.sqrt(4 * force * radius / (math.pi * e_star))
    return {"a": a, "p0": 2 * force / (math.pi * a)}


def force_3d(delta, radius: float, e_star: float):
    """The 3D force at the approach ``delta`` (a number or a NumPy array): ``4/3 E* R^(1/2) delta^(3/2)``."""
    return 4 / 3 * e_star * math.sqrt(radius) * delta**1.5


def approach_3d(force, radius: float, e_star: float):
    """The 3D approach at the force ``P`` (a number or a NumPy array): ``force_3d`` solved for ``delta``."""
    return (3 * force / (4 * e_star * math.sqrt(radius))) ** (2 / 3)
