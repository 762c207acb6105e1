"""Every tolerance and limit of the solve, named once, with its reason.

The algorithms read these from ``SolverSettings`` (a workspace's
``settings``, or ``DEFAULT`` for the helpers that have none) and hold no
numeric literals of their own. Lengths are relative to the largest play and
forces to the largest force (the problem is scaled to loads of unit norm),
unless a field says otherwise.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, replace


@dataclass(frozen=True)
class SolverSettings:
    """Knobs of the solve; the defaults are what the tests and the CLI use."""

    # -- what an answer must prove (the certificate) --------------------------
    #: Feasibility: no contact past its play by more than this fraction of the
    #: largest play. Also where a position counts as on a limit, past it, or
    #: moving at all: below it, a length is the solver's round-off.
    feasibility_tolerance: float = 1e-9
    #: Balance: per body, in newtons, relative to the largest force in the
    #: balance; also how far a force may fall below 0 or outside its cone.
    equilibrium_tolerance: float = 1e-8
    #: A contact this far from its reach (a fraction of its own play) is
    #: clear, and must push with nothing (to ``equilibrium_tolerance``):
    #: complementarity weighs a force by its slack only closer than this. The
    #: certificate's own (a route's thresholds below are apart from it, so
    #: that tuning a route never loosens what an answer must prove).
    clear: float = 1e-6

    # -- the interior-point method (Clarabel) ---------------------------------
    #: What an interior-point answer resolves, as a fraction of the size it
    #: is read against (about the square root of its gap): a cone within it
    #: of its apex rests there (a face flat, a ball centred; its force vector
    #: this far inside its cone); forces (loads of unit size) at this level
    #: are its round-off (rigid joints carrying the loads; the split's
    #: program leaving a contact unloaded); a body moving this little beside
    #: the biggest in its ray of unboundedness is left out of it first and
    #: not named as moving along.
    interior_resolution: float = 1e-6
    #: Gap and feasibility tolerances (relative, scaled problem): the answer
    #: then certifies on its own on every paper model.
    ipm_tolerance: float = 1e-10
    #: The one retry when an answer does not certify (a nearly degenerate
    #: mechanism), and the exact-rotation steps' tolerance.
    fine_ipm_tolerance: float = 1e-12
    #: Clarabel's static regularization of its KKT systems (its own default).
    ipm_regularization: float = 1e-8
    #: The retry's (and a tie's program's, below): the retry takes another
    #: path, not only a finer stop. On a degenerate optimum (bearing chains)
    #: the interior point stops "almost solved" on an active set that cannot
    #: all touch, at any tolerance; with this regularization it stops on
    #: another (``benchmarks/scan_degenerate.py`` counts the chains declined).
    #: A tie's least-norm program has it from the first try (so there the
    #: retry changes only the tolerance): its answer is printed as it is
    #: where its polish fails, and at 1e-8 a long bearing chain's program
    #: stops "almost solved" past a clearance (4.7e-9 mm on 4,000 shafts),
    #: sending the whole solve to the retry. It also takes fewer steps than
    #: at 1e-8 (4,000 shafts: 12 against 21).
    fine_ipm_regularization: float = 1e-10
    max_iterations: int = 200
    #: A large (sparse) model's interior point goes without the iterative
    #: refinement of its steps (to ``round_off``): there its
    #: answer is where Newton starts, which ends at round-off, and it doubles
    #: Clarabel's time (10,000-segment chain: 2.0 s and 16 iterations against
    #: 0.86 s and 11). So do its split rule's cone program, whose answer is
    #: refined on its support (10,000-shaft bearing chain: 3.6 s against 1.8 s
    #: in the same steps), and a tie's least-norm program, whose answer the
    #: polish starts from (there 3.7 s in 15 steps against 1.8 s in 13);
    #: where the refinement or the polish fails (degenerate bearing chains)
    #: their own answer is printed if it certifies. Not the rest position's
    #: least-norm program (no load), which stays refined. A small model's
    #: costs little, and degenerate ones need it (bearing chains of 17 to 21
    #: shafts are declined without it). An answer that does not certify is
    #: retried with it (``retry``), and a verdict (not held, not assembled)
    #: is read from a refined solve (``conic.run``); ``conic.refined``.
    sparse_interior_refinement: bool = False

    # -- rank and free motions -------------------------------------------------
    #: Singular values below this fraction of the largest count as zero: they
    #: span the free motions, dependent rows, indeterminate forces; a load
    #: component on a free motion below this fraction of the load is 0. So do
    #: the LU pivots of a Newton system (an active set's KKT matrix), though
    #: an LU is not rank revealing: with none below it the system is
    #: regular, its flat face pins the position and its rows are independent
    #: (on a hard model whose touching contacts are the face's, its forces
    #: are the split: ``faces.pins_by_newton``). Pivots measured:
    #: faces that pin x, 7.8e-3 to 0.35 on the examples, 1.5e-3 and 1.2e-3
    #: on 1,000- and 10,000-segment loops, 1.2e-7 on a 1,000-segment open
    #: string (its forces the least squares' to 4.7e-15); ties and redundant
    #: contacts factor not at all, or with pivots of 1e-13 and below.
    free_motion_rcond: float = 1e-9
    #: A body turning by more than this (rad) in the answer is reported as not
    #: held: a linear answer means nothing there. (Turns above 0.05 rad are
    #: answered with a warning, ``finite.py``; random mechanisms held by
    #: design reach 30 rad, a mechanism whose joints are nearly coincident or
    #: whose axes lean 1e-7 rad from a free motion 1e5 rad.)
    free_turn_rad: float = 1e3

    # -- polishing on the active set (Newton on the KKT equations) -------------
    #: Double-precision round-off of a well-scaled quantity: where Newton
    #: stops, what results and eliminations treat as an exact zero, and where
    #: the iterative refinement of each interior-point step's linear solve
    #: stops (with stiff springs pressed far past their play, Clarabel's
    #: default left some programs "AlmostSolved" at a 1e-7 gap). Also how
    #: far past its zone's edge a measured deviation is still on it: an edge
    #: written in decimals lands an ulp off (|(2, 2.1)| um against 2.9 um).
    round_off: float = 1e-14
    #: Regularization of a singular KKT system (loads of unit norm): small
    #: against every pivot of a well-posed one, large against round-off (its
    #: refinement then converges to the solution nearest the current point).
    kkt_round_off: float = 1e-12
    #: A plain KKT solve is refined until its residual is this small
    #: (relative to the right-hand side); a regularized one, ``kkt_refined``.
    kkt_plain: float = 1e-8
    kkt_refined: float = 1e-10
    #: Steps of iterative refinement after a KKT solve's one factorization
    #: (``linalg.solve_kkt``, and a large model's rigid forces'
    #: ``linalg.lstsq``): a regular system needs one or two; a regularized
    #: one shrinks its error by the shift over the pivot each step.
    kkt_refinements: int = 4
    #: Newton has stalled when a step gains less than this factor on the best
    #: of the three before it (round-off, or a slow mode of a long chain), and
    #: stops after at most ``newton_steps`` steps (from an interior point or a
    #: batch neighbour it takes a few; the force split's rows, the same).
    newton_stall: float = 0.5
    newton_steps: int = 30
    #: Newton on a face that pins the position is accepted when its
    #: equations hold to this (relative): well above where it stops, well
    #: below the certificate.
    newton_accept: float = 1e-11
    #: Newton runs on the interior point's active set, each correcting it
    #: (the contacts pushed past join, else the most negative force leaves):
    #: a degenerate bearing chain of 19 shafts drops one contact a run and
    #: needs 5; the example cases need one.
    newton_runs: int = 6
    #: An active force below this fraction of the largest is not strictly
    #: positive: its contact may leave the active set. The certificate's
    #: balance in value, apart from it in role: a stricter balance must not
    #: let round-off forces pin a position.
    positive_force: float = 1e-8
    #: Proximal weight of Newton's steps on a face that may be tied: the steps
    #: along the tie stay short ...
    tie_prox: float = 1e-9
    #: ... taken on a large system when a plain step goes this many times
    #: farther than the size of the position (or of the forces).
    far: float = 1e3

    #: mm: how far an envelope's support value may be from the optimum when
    #: Clarabel stalls just short of its tolerance ("AlmostSolved": a tilt
    #: zone on a prismatic guide, 1.1e-10 mm); far below the micrometres a
    #: tolerance study reads, and the point stays inside every clearance.
    support_gap: float = 1e-9
    #: Least squares (a singular KKT system's, the rigid joints' forces):
    #: singular values below this fraction of the largest are dropped
    #: (round-off, not rank); a sparse one is regularized by it.
    lstsq_rcond: float = 1e-13

    # -- exact rotations (``exact``) ------------------------------------------
    #: The exact geometry's overshoot of every clearance must stay below this
    #: (mm); a re-linearization step below ``exact_settle`` (mm) ends the
    #: iteration, after at most ``exact_max_steps``; ``exact_proximal`` damps
    #: its steps (loads of unit norm).
    exact_tolerance_mm: float = 1e-9
    exact_settle_mm: float = 1e-11
    exact_max_steps: int = 60
    exact_proximal: float = 1e-3
    #: Clarabel's iteration limit on an exact step's program (at the fine
    #: tolerance, nearly degenerate placements need more than the default).
    exact_ipm_iterations: int = 400

    # -- many loads at once (``batch``) ---------------------------------------
    #: A row that failed this many times from an active set's samples leaves
    #: that set (else every full solve would try every pending row again:
    #: time quadratic in the samples).
    batch_give_up: int = 6
    #: A start from before the batch (a Monte Carlo chunk's nominal answer)
    #: is given up when its set fails on every row of its first part, if the
    #: part has this many rows: samples come in random order, and a set that
    #: held for a tenth of them would miss 32 random rows 3 % of the time (a
    #: part of a few rows, on a large model, is no evidence).
    batch_guess_rows: int = 32

    @property
    def force_resolution(self) -> float:
        """Forces and moments print as 0 below this fraction of the largest
        force (round-off is 1e-12 of it and less): a hundredth of the balance,
        so that the components it zeroes change a body's balance by a small
        part of what ``equilibrium_tolerance`` allows (zeroing at the balance
        itself can unbalance a body past it)."""
        return self.equilibrium_tolerance / 100.0

    @property
    def touching(self) -> float:
        """A contact counts as touching when it uses this much of its own
        play: the certificate's feasibility, with room for a play 10x
        smaller than the largest."""
        return 1.0 - 10.0 * self.feasibility_tolerance

    def retry(self) -> SolverSettings:
        """The one retry's settings (an answer that does not certify, or a
        step of its route that cannot be done): finer, on another path (a
        tie's least-norm program has its regularization already), the
        interior point refined."""
        return replace(
            self,
            ipm_tolerance=self.fine_ipm_tolerance,
            ipm_regularization=self.fine_ipm_regularization,
            sparse_interior_refinement=True,
        )


DEFAULT = SolverSettings()

#: A positive floor for dividing by a size that may be 0 (not a tolerance:
#: any size it replaces is exactly 0).
TINY = 1e-300

#: Eigenvalues of a Gram matrix ``J^T J`` above this fraction of the largest
#: are above their round-off (a few ``m * eps`` of the largest) by orders of
#: magnitude, so ``J``'s singular values are surely above a rank tolerance
#: ``rcond`` whose square is far below it (``free_motion_rcond`` squared is
#: 1e-18): a rank test may trust them and leave only the rows below to the
#: SVD (not a tolerance of any answer: both routes give the SVD's verdict).
GRAM_CERTAIN = sys.float_info.epsilon**0.5
#: ... and above ``rcond`` squared by this factor (singular values above
#: twice ``rcond``): the bar when ``rcond`` is coarse.
GRAM_MARGIN = 4.0


# -- the studies (tolerances of a study's verdicts, not of any answer) -------

#: One-sided slopes differing by more than this (relative), and not converging
#: as the step halves, mark a kink.
KINK = 1e-6

#: Smallest probe force (N): a smaller one vanishes against the weights' round-off.
SMALLEST_PROBE = 1e-6

#: Largest error of the slopes' prediction, as a share of the linear stack's
#: half-width, for RSS to hold. A distance |d| bends over a fit's range or a
#: position zone (a norm of displacements that grow apart): on the bundled
#: examples whose contacts stay the same the error is at most 0.4 of the
#: half-width (shaft_deviations, where RSS's sigma is within 10 % of the
#: Monte Carlo's), most below 0.15; a change of contacts gives errors of the
#: half-width or many times it (the four-bar's out-of-plane force: 23 times).
LINEAR_ERROR_SHARE = 0.5

#: An error below this (mm) is round-off of a certified answer (1e-9 of a
#: clearance of 1 mm): a measure that does not vary is linear.
ROUND_OFF_MM = 1e-9

#: A sample passes the worst case only by more than this (mm): the
#: certificates' promise on every answer.
CERTIFIED_MM = 1e-6

#: A spread below this share of the measure's scale (its mean or its limit) is
#: round-off of a measure that does not vary: it counts as 0.
ROUND_OFF_SPREAD = 1e-12


@dataclass(frozen=True)
class MotionSettings:
    """Tolerances of the nominal kinematics (``jointplay.studies.kinematics``).
    Lengths are relative to the mechanism's size ``ell`` (the diagonal of the
    box around its joints); a rotation's equation is written as the length it
    moves a point ``ell`` away, so that every equation is a length."""

    #: A pose closes its loops when no ideal equation is off by more than this
    #: (times ``ell``): double precision resolves a closed loop to about 1e-15
    #: of its size, and a closed-form pose is met to well below 1e-9 mm on a
    #: 1 m linkage; a pose off by more than this has no solution there (the
    #: drive's value is out of the linkage's reach).
    closure: float = 1e-10
    #: Least squares stop when a step changes the pose or the residual by less
    #: than this (relative). What is left after such a step is below the step
    #: itself (1e-12 of the pose's change, ~1e-11 mm), far inside the 1e-9 mm
    #: the closed forms are met to; where the convergence is quadratic (away
    #: from a toggle) the pose is closed to round-off. Tighter stops only
    #: repeat steps at round-off (the four-bar's turn: 628 evaluations at
    #: 1e-15, 381 at 1e-12, the same poses to 2e-13 mm).
    solve_tolerance: float = 1e-12
    #: At most this many evaluations of the equations per step (a pose that
    #: closes takes a few; Levenberg-Marquardt's own default is 100 per unknown).
    evaluations: int = 2000
    #: The drive no longer decides the pose (a dead point) when the smallest
    #: singular value of the equations' Jacobian, drive included, falls below
    #: this fraction of the largest. At a toggle it goes as the square root of
    #: the distance to it: the round-off of a closed pose (1e-15) leaves about
    #: 3e-8, and a pose 1e-12 of the range short of the toggle is ``1e-6``.
    dead_point: float = 1e-6
    #: A motion of the bodies that moves no ideal equation by more than this
    #: fraction of the largest singular value is free (the drive leaves it
    #: undecided): the rank test of the solver's free motions.
    mobility_rcond: float = 1e-9
    #: The largest change of the drive a step's solve starts from the previous
    #: pose with (rad for a spin; times ``ell`` in mm for a slide): longer steps
    #: are taken in parts, so that least squares start near the pose they close
    #: (from 90 deg away a slider-crank's loop closes on its other branch).
    largest_step: float = 0.1
    #: Where a step cannot close, the end of the drive's reach is found by
    #: bisection to this (rad for a spin; times ``ell`` in mm for a slide):
    #: 30 closes from a part of a step (``largest_step``), each cheap; below
    #: it a value closes or not by the ``closure`` of the pose (1e-10), not by
    #: the linkage. The end is then shown to 6 significant digits.
    reach_resolution: float = 1e-10
    #: The end of the reach is a toggle (a dead point: the drive cannot pass
    #: it) when the equations' smallest singular value there, drive included,
    #: is below this fraction of the largest. Within ``reach_resolution`` of a
    #: toggle it is at most ~1e-5 (it goes as the square root of the
    #: distance; 7e-11 and 3e-10 measured at the ends of the rocker and the
    #: crank of tests/test_motion.py's reach tests, where the closing pose
    #: sits on the toggle itself); away from one a linkage's is far above
    #: this (the four-bar's 0.05 at its written pose, 0.004 still 0.1 deg
    #: short of its toggle).
    toggle: float = 1e-3


MOTION = MotionSettings()

#: The most steps a motion may have: each is a solve, and 100,000 poses (a
#: point every 0.0036 deg of a turn) are far past any curve's need.
MOST_MOTION_STEPS = 100_000
