"""The numeric core: from an assembled model to a certified equilibrium.

Layers, bottom up, each importing only those below: ``records`` (points,
faces, cone programs: plain data); ``workspace`` (one model's matrices, free
motions and balance maps, made once); ``faces``, ``held`` (motions the
joints do not hold) and ``certificate`` (the one check every answer
passes); ``conic`` (Clarabel's statuses) and ``newton``; ``ties`` and
``forces`` (the documented split of hyperstatic forces); ``pipeline`` (the
single solve); ``batch`` (many loads and plays at once) and ``exact``
(finite rotations); ``solve`` (the public ``Workspace``, ``solve`` and
``solve_cases``, which ``jointplay`` hands on). This file imports none of
them, so that importing a lower layer loads no higher one. See
docs/solver.md."""
