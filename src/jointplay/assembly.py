"""One path from a model to a cone program, with a map back to joints and contacts.

Unknowns. Each moving body b gets a 6-vector of *scaled* unknowns
``x_b = (V_b / s, Omega_b * ell / s)``: ``V_b`` the translation of the body
point at its reference point ``c_b`` (the centroid of its joint centres),
``Omega_b`` its rotation vector. ``s`` is a displacement scale (the largest
play), ``ell`` a length scale of the mechanism. Working at ``c_b`` rather than
at the global origin keeps far-away parts well conditioned; results are
reported at the global origin.

Everything the solver needs is linear in ``x``:

* ``G_joint @ x`` is a joint's relative torsor ``(t [mm], w [rad])`` of b with
  respect to a, at the joint centre, in the joint frame;
* each contact is ``|| A @ x || <= radius`` (scaled by ``s``), or ``A @ x = 0``;
* the loads' work is ``g @ x`` (N*mm), so the potential energy is ``-g @ x``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from .geometry import FloatArray, skew
from .joints import Contact, Joint
from .model import Model

IntArray = NDArray[np.intp]


@dataclass(frozen=True)
class JointMap:
    """A joint's (6, m) map from scaled unknowns to its relative torsor
    ``(t mm, w rad)``, stored compactly: only the columns of its two bodies."""

    cols: IntArray
    block: FloatArray  # (6, len(cols))
    m: int

    def apply(self, x: FloatArray) -> FloatArray:
        return self.block @ x[self.cols]

    def __matmul__(self, x: FloatArray) -> FloatArray:
        return self.apply(x)

    def sparse(self) -> sp.csr_matrix:
        return _scatter(self.block, self.cols, self.m)


@dataclass(frozen=True)
class ContactRows:
    """Where one contact of one joint sits in the cone program: its rows
    ``A = rows @ G_joint / s`` (scaled), kept on the joint's columns only."""

    joint_index: int
    contact_index: int
    contact: Contact
    cols: IntArray
    block: FloatArray  # (k, len(cols))
    radius: float  # scaled: contact.radius / s
    m: int

    @property
    def is_fixed(self) -> bool:
        return self.contact.kind == "fixed" or self.radius == 0.0

    @property
    def k(self) -> int:
        return int(self.block.shape[0])

    def apply(self, x: FloatArray) -> FloatArray:
        """``A @ x``."""
        return self.block @ x[self.cols]

    def adjoint(self, u: FloatArray) -> FloatArray:
        """``A.T @ u`` as a full m-vector."""
        out = np.zeros(self.m)
        np.add.at(out, self.cols, self.block.T @ u)
        return out

    def dense(self) -> FloatArray:
        out = np.zeros((self.k, self.m))
        np.add.at(out.T, self.cols, self.block.T)
        return out

    @cached_property
    def A(self) -> sp.csr_matrix:
        return _scatter(self.block, self.cols, self.m)


def _scatter(block: FloatArray, cols: IntArray, m: int) -> sp.csr_matrix:
    k = block.shape[0]
    rows = np.repeat(np.arange(k), len(cols))
    return sp.csr_matrix((block.ravel(), (rows, np.tile(cols, k))), shape=(k, m))


@dataclass(frozen=True)
class Assembly:
    """The model turned into matrices, once; the solver reads only this."""

    model: Model
    body_names: tuple[str, ...]  # moving bodies, in unknown-block order
    body_ref: FloatArray  # (n, 3) reference point c_b of each moving body (mm)
    s: float  # mm per unit of scaled translation
    ell: float  # mm: rotation lever of the scaling and of the least-norm metric
    G: tuple[JointMap, ...]  # per joint: scaled x -> (t mm, w rad) in joint frame
    contacts: tuple[ContactRows, ...]
    g: FloatArray  # (m,) work of the loads per unit scaled x (N*mm)

    @property
    def m(self) -> int:
        return 6 * len(self.body_names)

    @cached_property
    def balls(self) -> tuple[ContactRows, ...]:
        return tuple(c for c in self.contacts if not c.is_fixed)

    @cached_property
    def fixed(self) -> tuple[ContactRows, ...]:
        return tuple(c for c in self.contacts if c.is_fixed)

    @cached_property
    def E(self) -> sp.csr_matrix:
        """Equality rows (rigid joints and zero-clearance contacts)."""
        if not self.fixed:
            return sp.csr_matrix((0, self.m))
        return sp.vstack([c.A for c in self.fixed], format="csr")

    @cached_property
    def metric(self) -> sp.csc_matrix:
        """Least-norm metric: sum over joints of |t/s|^2 + |w * ell / s|^2.

        It measures the relative motion in the joints, so it does not change
        under a rigid motion of the whole model or a change of units, and a
        rigid joint (no relative motion) adds nothing to it.
        """
        w = np.r_[np.full(3, 1.0 / self.s), np.full(3, self.ell / self.s)]
        rows, cols, vals = [], [], []
        for G in self.G:
            wb = w[:, None] * G.block
            local = wb.T @ wb
            rows.append(np.repeat(G.cols, len(G.cols)))
            cols.append(np.tile(G.cols, len(G.cols)))
            vals.append(local.ravel())
        return sp.csc_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
            shape=(self.m, self.m),
        )

    def scale_matrix(self) -> FloatArray:
        """Physical (V_c mm, Omega rad) per body from scaled x: ``x_phys = D * x``."""
        per_body = np.r_[np.full(3, self.s), np.full(3, self.s / self.ell)]
        return np.tile(per_body, len(self.body_names))

    def body_motion(self, x: FloatArray, i: int) -> tuple[FloatArray, FloatArray]:
        """(rotation rad, translation at global origin mm) of moving body ``i``."""
        v_ref = self.s * x[6 * i : 6 * i + 3]
        omega = (self.s / self.ell) * x[6 * i + 3 : 6 * i + 6]
        return omega, v_ref - np.cross(omega, self.body_ref[i])


def assemble(model: Model) -> Assembly:
    body_names = tuple(b.name for b in model.moving_bodies)
    index = {name: i for i, name in enumerate(body_names)}
    n = len(body_names)
    m = 6 * n

    centres: list[list[FloatArray]] = [[] for _ in range(n)]
    for joint in model.joints:
        for name in joint.between:
            if name in index:
                centres[index[name]].append(joint.centre)
    body_ref = np.array([np.mean(c, axis=0) for c in centres]).reshape(n, 3)

    # Rigid joints add nothing to the metric, so they do not set its length scale:
    # splitting a body with a weld anywhere leaves every answer unchanged.
    with_play = [j for j in model.joints if any(c.kind == "ball" for c in j.contacts())]
    all_centres = np.array([j.centre for j in (with_play or model.joints)])
    spread = float(np.max(np.linalg.norm(all_centres - all_centres.mean(axis=0), axis=1)))
    radii = [c.radius for j in model.joints for c in j.contacts() if c.kind == "ball"]
    s = max(radii, default=0.0)
    sizes = [j.size for j in with_play]
    if s == 0.0:  # every joint is tight: any length of the model will do
        s = max([spread, *sizes, 1.0])
    ell = max([spread, *sizes, s])

    G_list: list[JointMap] = []
    contacts: list[ContactRows] = []
    for jdx, joint in enumerate(model.joints):
        G = _joint_map(joint, index, body_ref, s, ell, m)
        G_list.append(G)
        for cdx, contact in enumerate(joint.contacts()):
            block = (contact.rows / s) @ G.block
            contacts.append(ContactRows(jdx, cdx, contact, G.cols, block, contact.radius / s, m))

    g = np.zeros(m)
    for load in model.loads:
        i = index[load.body]
        force = np.zeros(3) if load.force is None else np.array(load.force)
        torque = np.zeros(3) if load.torque is None else np.array(load.torque)
        moment = torque.copy()
        if load.at is not None:
            moment += np.cross(np.array(load.at) - body_ref[i], force)
        g[6 * i : 6 * i + 3] += s * force
        g[6 * i + 3 : 6 * i + 6] += (s / ell) * moment

    return Assembly(model, body_names, body_ref, s, ell, tuple(G_list), tuple(contacts), g)


def _joint_map(
    joint: Joint, index: dict[str, int], body_ref: FloatArray, s: float, ell: float, m: int
) -> JointMap:
    """The map from scaled unknowns to the relative torsor of b w.r.t. a at the joint."""
    R_joint_world = joint.R_world_joint.T
    cols: list[IntArray] = []
    blocks: list[FloatArray] = []
    for sign, name in ((-1.0, joint.between[0]), (1.0, joint.between[1])):
        if name not in index:
            continue  # ground body
        i = index[name]
        lever = joint.centre - body_ref[i]
        block = np.zeros((6, 6))
        block[:3, :3] = s * R_joint_world
        block[:3, 3:] = -(s / ell) * R_joint_world @ skew(lever)
        block[3:, 3:] = (s / ell) * R_joint_world
        cols.append(np.arange(6 * i, 6 * i + 6))
        blocks.append(sign * block)
    return JointMap(np.concatenate(cols), np.hstack(blocks), m)
