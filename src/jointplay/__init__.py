"""jointplay: where the parts of a mechanism really sit when its joints have play.

>>> import jointplay
>>> model = jointplay.load("examples/paper/6.1.6.1.yaml")
>>> result = jointplay.solve(model)
>>> result.joints["l1"].translation  # mm, in the joint frame
"""

from typing import TYPE_CHECKING

from jointplay.errors import (
    JointplayError,
    ModelError,
    OptionError,
    SolverError,
    UnboundedMechanismError,
)
from jointplay.version import __version__

if TYPE_CHECKING:
    from jointplay.io.modelfile import load, model_from_dict, with_deviations
    from jointplay.model.joints import JOINT_TYPES, Joint
    from jointplay.model.mechanism import Body, Load, Model
    from jointplay.present.report import Report
    from jointplay.result import (
        BodyResult,
        Certificate,
        ContactResult,
        JointResult,
        RequirementResult,
        Result,
    )
    from jointplay.settings import SolverSettings
    from jointplay.solver.batch import BatchSolution
    from jointplay.solver.solve import Workspace, solve, solve_cases
    from jointplay.studies.contributions import Contributions, ContributionsResult
    from jointplay.studies.envelope import Envelope, EnvelopeResult
    from jointplay.studies.montecarlo import MonteCarlo, MonteCarloResult
    from jointplay.studies.motion import Motion, MotionResult
    from jointplay.studies.motion_studies import (
        MotionContributions,
        MotionContributionsResult,
        MotionEnvelope,
        MotionEnvelopeResult,
        MotionMonteCarlo,
        MotionMonteCarloResult,
        MotionStudiesResult,
    )
    from jointplay.studies.sweep import RotateLoad, Sweep, SweepResult, Vary
    from jointplay.studies.tolerances import Tolerances, TolerancesResult

#: Where each name of the API lives, imported on first use: ``import jointplay``
#: (and so every command's start, ``--help`` included) loads only the errors;
#: the solver brings NumPy, SciPy and Clarabel, the studies SciPy's statistics
#: and pandas.
_LAZY = {
    "load": "io.modelfile",
    "model_from_dict": "io.modelfile",
    "with_deviations": "io.modelfile",
    "JOINT_TYPES": "model.joints",
    "Joint": "model.joints",
    "Body": "model.mechanism",
    "Load": "model.mechanism",
    "Model": "model.mechanism",
    "BodyResult": "result",
    "Certificate": "result",
    "ContactResult": "result",
    "JointResult": "result",
    "RequirementResult": "result",
    "Result": "result",
    "SolverSettings": "settings",
    "BatchSolution": "solver.batch",
    "solve": "solver.solve",
    "solve_cases": "solver.solve",
    "Workspace": "solver.solve",
    "Motion": "studies.motion",
    "MotionResult": "studies.motion",
    "MotionMonteCarlo": "studies.motion_studies",
    "MotionMonteCarloResult": "studies.motion_studies",
    "MotionEnvelope": "studies.motion_studies",
    "MotionEnvelopeResult": "studies.motion_studies",
    "MotionContributions": "studies.motion_studies",
    "MotionContributionsResult": "studies.motion_studies",
    "MotionStudiesResult": "studies.motion_studies",
    "MonteCarlo": "studies.montecarlo",
    "MonteCarloResult": "studies.montecarlo",
    "Envelope": "studies.envelope",
    "EnvelopeResult": "studies.envelope",
    "Sweep": "studies.sweep",
    "SweepResult": "studies.sweep",
    "Vary": "studies.sweep",
    "RotateLoad": "studies.sweep",
    "Contributions": "studies.contributions",
    "ContributionsResult": "studies.contributions",
    "Report": "present.report",
    "Tolerances": "studies.tolerances",
    "TolerancesResult": "studies.tolerances",
}


#: The package's modules, which ``jointplay.NAME`` reaches as before.
_MODULES = (
    "assembly",
    "cli",
    "finite",
    "geometry",
    "io",
    "model",
    "numerics",
    "present",
    "result",
    "settings",
    "solver",
    "studies",
    "units",
)


def __getattr__(name: str) -> object:
    import importlib

    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value  # found once; later lookups are plain
        return value
    if name in _MODULES:
        return importlib.import_module(f".{name}", __name__)
    raise AttributeError(f"module 'jointplay' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__, *_MODULES})


__all__ = [
    "JOINT_TYPES",
    "BatchSolution",
    "Body",
    "BodyResult",
    "Certificate",
    "ContactResult",
    "Contributions",
    "ContributionsResult",
    "Envelope",
    "EnvelopeResult",
    "Joint",
    "JointResult",
    "JointplayError",
    "Load",
    "Model",
    "ModelError",
    "MonteCarlo",
    "MonteCarloResult",
    "Motion",
    "MotionContributions",
    "MotionContributionsResult",
    "MotionEnvelope",
    "MotionEnvelopeResult",
    "MotionMonteCarlo",
    "MotionMonteCarloResult",
    "MotionResult",
    "MotionStudiesResult",
    "OptionError",
    "Report",
    "RequirementResult",
    "Result",
    "RotateLoad",
    "SolverError",
    "SolverSettings",
    "Sweep",
    "SweepResult",
    "Tolerances",
    "TolerancesResult",
    "UnboundedMechanismError",
    "Vary",
    "Workspace",
    "__version__",
    "load",
    "model_from_dict",
    "solve",
    "solve_cases",
    "with_deviations",
]
