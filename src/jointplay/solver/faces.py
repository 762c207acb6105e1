"""Active sets: which contacts hold a candidate optimum, and the face of
positions they leave.

A ``Face`` (``records``) is an active set's equations, built once per
workspace and kept (``WorkspaceData.faces``): the batch and the single
solves meet the same sets again and again. Whether a face pins the position down decides between a
plain Newton polish and the least-norm rule for ties (``ties.py``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from jointplay.assembly import BallStack
from jointplay.geometry import FloatArray
from jointplay.numerics import free_motions, linalg
from jointplay.numerics.linalg import Matrix
from jointplay.settings import TINY
from jointplay.solver.records import Face, FaceKey, Point

if TYPE_CHECKING:
    from jointplay.solver.workspace import WorkspaceData


def pins_by_newton(point: Point) -> bool:
    """Whether Newton's own system on ``point``'s active set says its face
    pins x (and that the face's rows are independent); False when it says
    nothing (the set changed since, or the system was not regular)."""
    return point.active is not None and point.regular_on == point.active


def face_of(ws: WorkspaceData, key: FaceKey) -> Face:
    """The face of the active set ``key`` (built on first use, then kept)."""
    face = ws.faces.get(key)
    if face is None:
        surface, linear = key
        stack = ws.stack
        sub = stack.take(surface)
        lin = stack.take(linear)
        k = lin.k
        n_l, n_f = int(np.sum(k)) + len(k), int(np.sum(k))
        rhs = np.zeros(n_l)
        first = (lin.start + np.arange(len(k))).astype(np.intp)  # each cone's A rows, then B
        lam_rows = first + k
        f_rows = lin.rows_of(np.arange(len(k))) + np.repeat(np.arange(len(k)), k)
        order = np.empty(n_l, dtype=np.intp)  # row of L -> row of (A; B)
        order[f_rows] = np.arange(n_f)
        order[lam_rows] = n_f + np.arange(len(k))
        L = linalg.vstack([lin.A, lin.B], ws.m)[order]
        rhs[lam_rows] = lin.r
        rhs[f_rows] = lin.centres()
        tilting = bool(np.any(sub.has_offset & (sub.k > 0)))

        def determined(L: Matrix = L, sub: BallStack = sub) -> bool | None:
            if tilting:
                return None
            return pins_position(ws, linalg.vstack([L, sub.A], ws.m))

        def ties(L: Matrix = L, sub: BallStack = sub) -> FloatArray | None:
            if ws.sparse:
                return None
            rows = linalg.dense(linalg.vstack([ws.Eq, L, sub.A], ws.m))
            free = linalg.null_space(
                rows, ws.m, ws.settings.free_motion_rcond, ws.settings.round_off
            )
            return np.asarray(ws.asm.metric_times(linalg.dense(free)).T)

        face = Face(
            key,
            sub,
            L,
            rhs,
            lam_rows,
            f_rows,
            linalg.vstack([ws.Eq, L], ws.m),
            np.concatenate([np.zeros(ws.Eq.shape[0]), rhs]),
            stack.rows_of(surface),
            stack.rows_of(linear),
            tilting,
            determined,
            ties,
        )
        ws.faces[key] = face
    return face


def pins_position(ws: WorkspaceData, rows: Matrix) -> bool:
    """Whether ``rows`` with the workspace's equalities leave no motion free.

    ``rows`` are contact rows, so the free motions ``N`` move none of them,
    and with the rows ``K`` that pin N they pin x exactly when they and the
    joints' equalities ``E`` leave N's motions free and no others. A large
    mechanism is tested that way: K's rows go through the least-norm metric,
    which couples neighbours, and eliminating them costs a round per pair of
    bodies (a 1,000-shaft chain: 501 rounds against 10). The count is taken
    at the free motions' own threshold (relative to every limit row's
    scale): at the rows' own, smaller, one a motion N holds weakly could be
    counted as held and hide one the rows leave free (a review)."""
    if ws.sparse:
        return bool(_eliminated(ws, rows).deficit <= ws.N.shape[1])
    all_rows = linalg.vstack([ws.Eq, rows], ws.m)
    return linalg.full_column_rank(all_rows, ws.m, ws.settings.free_motion_rcond)


def _eliminated(ws: WorkspaceData, rows: Matrix) -> free_motions.Eliminated:
    """The elimination of ``rows`` with the joints' equalities ``E``, at the
    free motions' threshold (``pins_position``)."""
    C = linalg.vstack([ws.E, rows], ws.m)
    return free_motions.Eliminated(C, ws.m, ws.settings.free_motion_rcond, ws.limit_scale)


def is_determined(ws: WorkspaceData, face: Face, x: FloatArray) -> bool:
    """Whether the optimum on ``face`` is unique. On a tilting face
    (``|A_i x| + B_i x = r_i`` with ``B_i != 0``) two optima may trade
    tilt for shift along ``(A_i d, B_i d) ~ (u_i, -1)``, so only the rows
    of ``(A_i; B_i)`` across that direction count; they depend on x."""
    if face.determined is not None:
        return face.determined
    rows = _held_rows(ws, face, x)
    return rows is not None and pins_position(ws, rows)


def _held_rows(ws: WorkspaceData, face: Face, x: FloatArray) -> Matrix | None:
    """The rows whose motions ``face`` holds at ``x`` (``is_determined``);
    None when a tilting cone rests at its apex (it holds no direction)."""
    sub = face.stack
    v, rho = sub.norms(x)
    plain = np.flatnonzero(~sub.has_offset)  # all at once: a long chain has 40,000
    rows = [face.L, sub.A[sub.rows_of(plain)]]
    for i in np.flatnonzero(sub.has_offset).tolist():
        if rho[i] == 0.0:
            return None
        w = np.append(v[sub.start[i] : sub.start[i] + sub.k[i]] / rho[i], -1.0) / np.sqrt(2)
        M = linalg.dense(sub.face_rows(i))
        rows.append(M - np.outer(w, w @ M))
    return linalg.vstack(rows, ws.m)


def determined_rows(
    ws: WorkspaceData, face: Face, x: FloatArray, centre: FloatArray
) -> NDArray[np.bool_]:
    """``is_determined`` for each row of ``x`` (B, m), the cones' centres
    rows of ``centre`` (dense models): one stack of rows per row, whose
    tilting cones' rows depend on it, and their ranks at once."""
    B = len(x)
    if face.determined is not None:
        return np.full(B, bool(face.determined))
    sub = face.stack
    v, rho = sub.norms(x, centre)
    fixed = [linalg.dense(ws.Eq), linalg.dense(face.L)]
    fixed += [linalg.dense(sub.cone_rows(i)) for i in range(len(sub.k)) if not sub.has_offset[i]]
    rows = [np.broadcast_to(np.vstack(fixed), (B, *np.vstack(fixed).shape))]
    ok = np.ones(B, dtype=bool)
    for i in np.flatnonzero(sub.has_offset):
        at = slice(sub.start[i], sub.start[i] + sub.k[i])
        ok &= rho[:, i] > 0.0
        u = v[:, at] / np.where(rho[:, i : i + 1] > 0, rho[:, i : i + 1], 1.0)
        w = np.hstack([u, -np.ones((B, 1))]) / np.sqrt(2)
        M = linalg.dense(sub.face_rows(int(i)))
        rows.append(M[None] - w[:, :, None] * (w @ M)[:, None, :])
    stacked = np.concatenate(rows, axis=1)
    if stacked.shape[1] < ws.m:
        return np.zeros(B, dtype=bool)
    return ok & linalg.full_column_rank_rows(stacked, ws.settings.free_motion_rcond)


def rimless_forces(stack: BallStack, linear: list[int], lam: FloatArray, f: FloatArray) -> None:
    """A hard cone at its apex with no rim (``BallStack.has_rim``) pushes
    with ``|f_i|``: its row ``B_i x = r_i`` is empty, and any ``lam_i >=
    |f_i|`` is a multiplier (the interior point's, or Newton's round-off).
    Rows of ``lam`` and ``f`` (or one), in place."""
    rimless = [i for i in linear if stack.k[i] and not stack.has_rim[i] and stack.spring[i] == 0]
    if rimless:
        sub = stack.take(rimless)
        lam[..., rimless] = np.sqrt(sub.segment_sum(f[..., stack.rows_of(rimless)] ** 2))


def active_set(
    ws: WorkspaceData,
    x: FloatArray,
    lam: FloatArray,
    f: FloatArray,
    stack: BallStack,
    lam_scale: float | None = None,
) -> FaceKey:
    """Contacts whose multiplier outweighs their slack (both relative),
    split into those on their cone's surface and those at its apex (or
    with no rows): see ``Face``. Multipliers are relative to the largest,
    or to ``lam_scale`` if that is larger (when rigid joints carry the
    loads, the contacts' multipliers are round-off)."""
    if len(lam) == 0:
        return (), ()
    st = ws.settings
    floor = st.interior_resolution if lam_scale is None else lam_scale
    lam_max = max(float(np.max(lam)), floor, TINY)
    _, rho, level = stack.levels(x)
    r = np.where(stack.r > 0, stack.r, ws.max_radius)
    slack = (stack.r - level) / r
    held = np.flatnonzero(lam / lam_max > np.maximum(slack, st.feasibility_tolerance))
    f_norm = np.sqrt(stack.segment_sum(f * f))
    apex = (stack.k == 0) | (
        (rho <= st.interior_resolution * r)
        & (f_norm < (1.0 - st.interior_resolution) * np.maximum(lam, 0.0))
    )
    surface = tuple(int(i) for i in held if not apex[i])
    linear = tuple(int(i) for i in held if apex[i])
    return surface, linear
