"""One certificate for every answer: single solves, batches and each route inside them.

An answer is positions ``x`` and multipliers (``lam``, ``f`` per contact cone,
``nu`` per rigid row) of the scaled problem with unit loads ``g_hat``. It is
an optimum of the convex program exactly when these hold (its KKT
conditions), each checked from the problem data and the answer alone:

- *feasibility*: no contact past its reach (its play, plus a compliant
  contact's penetration ``sigma_i lam_i``), rigid rows held;
- *balance*: on every moving body, loads and contact forces balance, in
  newtons: the worst body's imbalance (force, and moment over the length
  ``ell``) relative to the largest force in the balance (a body's load
  resultant, or a joint's reaction);
- *forces*: every contact pushes (``lam_i >= 0``) with its force vector in
  its cone (``|f_i| <= lam_i``);
- *complementarity*: a contact that does not touch pushes with nothing, and
  one that touches pushes along its direction of contact.

Rows are checked together (a single answer is a batch of one).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from jointplay.geometry import FloatArray
from jointplay.numerics import linalg
from jointplay.result import Certificate

if TYPE_CHECKING:
    from jointplay.settings import SolverSettings
    from jointplay.solver.records import Point
    from jointplay.solver.workspace import WorkspaceData


@dataclass(frozen=True)
class Checks:
    """The certificate's quantities, one entry per row (see module doc)."""

    feasibility: FloatArray  # scaled length: the worst of ``overshoot`` and ``opening``, if any
    overshoot: FloatArray  # scaled length: the worst contact past its reach
    opening: FloatArray  # scaled length: the widest rigid row apart, |E x| over its lever
    balance: FloatArray  # relative to the largest force in the balance
    min_force: FloatArray  # scaled force: the smallest lam
    outside: FloatArray  # scaled force: the largest |f_i| - lam_i
    complementarity: FloatArray  # scaled force times length, over the largest radius
    force_scale: FloatArray  # max(1, largest |lam|): what the force checks are relative to
    nu: FloatArray  # the rigid rows' multipliers used (given, or least squares)

    def limits(self, settings: SolverSettings, max_radius: float) -> dict[str, FloatArray]:
        """Each check's limit, per row: lengths in the scaled unknowns,
        forces relative to ``force_scale`` (``min_force``'s is its floor)."""
        tol, reach = settings.equilibrium_tolerance, settings.feasibility_tolerance * max_radius
        forces = tol * self.force_scale
        each = np.ones_like(self.balance)
        return {
            "overshoot": reach * each,
            "opening": reach * each,
            "balance": tol * each,
            "min_force": -forces,
            "outside": forces,
            "complementarity": forces,
        }

    def failed(self, settings: SolverSettings, max_radius: float) -> dict[str, NDArray[np.bool_]]:
        """Each check's failures, per row (a NaN fails)."""
        limit = self.limits(settings, max_radius)
        return {
            name: ~(self.min_force >= limit[name])
            if name == "min_force"
            else ~(getattr(self, name) <= limit[name])
            for name in limit
        }

    def passed(self, settings: SolverSettings, max_radius: float) -> NDArray[np.bool_]:
        ok = np.ones(len(self.balance), dtype=bool)
        for bad in self.failed(settings, max_radius).values():
            ok &= ~bad
        return ok


def check(
    ws: WorkspaceData,
    g_hat: FloatArray,
    x: FloatArray,
    lam: FloatArray,
    f: FloatArray,
    sigma: FloatArray,
    r: FloatArray | None = None,
    nu: FloatArray | None = None,
    c: FloatArray | None = None,
) -> Checks:
    """The certificate of B answers (rows of ``x``, ``lam``, ``f``; ``nu``:
    rigid multipliers, else least squares) under unit loads ``g_hat`` (rows),
    with contact softness ``sigma`` and, if given, each row's own radii ``r``
    and cone centres ``c``."""
    stack = ws.stack
    B = x.shape[0]
    radii = stack.r if r is None else r  # broadcast against the rows below
    if len(stack.k):
        v, rho, level = stack.levels(x, c)
        reach = radii + sigma * np.maximum(lam, 0.0)
        feas = (level - reach).max(axis=1)
        # each contact's over its own reach: a faint force on a small play
        # left clear is not hidden by a large play elsewhere; and a contact
        # clear by more than ``clear`` of it pushes with nothing at all
        # (the exact route's cones, linearized at a placement, move the
        # contact's offset into their radii: its own play stays ``ws.plays``)
        play = ws.plays if r is None else r
        own_reach = play + sigma * np.maximum(lam, 0.0)
        own = np.where(own_reach > 0, own_reach, ws.max_radius)
        slack = np.abs(reach - level) / own
        slack = np.where(slack > ws.settings.clear, 1.0, slack)
        turned = np.abs(lam * rho - stack.segment_sum(f * v)) / own
        comp = (np.abs(lam) * slack + turned).max(axis=1)
        min_force = lam.min(axis=1)
        outside = (np.sqrt(stack.segment_sum(f * f)) - lam).max(axis=1)
        force_scale = np.maximum(1.0, np.abs(lam).max(axis=1))
    else:
        feas = comp = min_force = outside = np.zeros(B)
        force_scale = np.ones(B)
    opening, worst = np.zeros(B), feas  # a contact's overshoot may be negative: inside
    if ws.E.shape[0]:
        opening = (np.abs(linalg.times(ws.E, x)) * ws.asm.E_length).max(axis=1)
        worst = np.maximum(feas, opening)
    balance, nu_used = ws.balance.residual(g_hat, lam, f, nu)
    return Checks(
        worst,
        feas,
        opening,
        balance,
        min_force,
        outside,
        comp,
        force_scale,
        nu_used,
    )


def certify(
    ws: WorkspaceData,
    g_hat: FloatArray,
    sigma: FloatArray,
    point: Point,
    nu: FloatArray | None = None,
) -> Certificate:
    """The certificate (``certificate.check``) of one answer."""
    c = check(
        ws,
        g_hat[None],
        point.x[None],
        point.lam[None],
        point.f[None],
        sigma[None],
        nu=None if nu is None else nu[None],
    )
    return Certificate(
        certified=bool(c.passed(ws.settings, ws.max_radius)[0]),
        method=point.method,
        feasibility_mm=max(float(c.feasibility[0]), 0.0) * ws.asm.s,
        equilibrium_residual=float(c.balance[0]),
        complementarity=float(c.complementarity[0]),
        min_force=float(c.min_force[0]),
        iterations=point.iterations,
    )


def refusal(ws: WorkspaceData, g_hat: FloatArray, sigma: FloatArray, point: Point) -> str:
    """What the answer ``point`` fails of its certificate, in words: each
    check it fails, with its value and its limit (for a decline's message)."""
    nu = None if point.nu is None else point.nu[None]
    c = check(ws, g_hat[None], point.x[None], point.lam[None], point.f[None], sigma[None], nu=nu)
    failed = c.failed(ws.settings, ws.max_radius)
    limit = {name: float(v[0]) for name, v in c.limits(ws.settings, ws.max_radius).items()}
    mm = ws.asm.s
    words = {
        "overshoot": f"a contact {c.overshoot[0] * mm:.3g} mm past its clearance "
        f"({limit['overshoot'] * mm:.3g} allowed)",
        "opening": f"a rigid joint open by {c.opening[0] * mm:.3g} mm "
        f"({limit['opening'] * mm:.3g} allowed)",
        "balance": f"the forces balance the loads on each body only to {c.balance[0]:.3g} of "
        f"the largest force ({limit['balance']:g} asked)",
        "min_force": f"a contact pulls ({-c.min_force[0]:.3g} of the loads, "
        f"{-limit['min_force']:.3g} allowed)",
        "outside": f"a contact's force leaves its cone by {c.outside[0]:.3g} of the loads "
        f"({limit['outside']:.3g} allowed)",
        "complementarity": "a contact that does not touch pushes "
        f"({c.complementarity[0]:.3g} of the loads, {limit['complementarity']:.3g} allowed)",
    }
    return "; ".join(words[name] for name in words if failed[name][0])
