"""jointplay: where the parts of a mechanism really sit when its joints have play.

>>> import jointplay
>>> model = jointplay.load("examples/paper/6.1.6.1.yaml")
>>> result = jointplay.solve(model)
>>> result.joints["l1"].translation  # mm, in the joint frame
"""

from typing import TYPE_CHECKING

from .batch import BatchSolution
from .errors import (
    JointplayError,
    ModelError,
    OptionError,
    SolverError,
    UnboundedMechanismError,
)
from .joints import JOINT_TYPES, Joint
from .model import Body, Load, Model
from .modelfile import load, model_from_dict
from .result import BodyResult, Certificate, ContactResult, JointResult, Result
from .settings import SolverSettings
from .solver import Workspace, solve, solve_cases

if TYPE_CHECKING:
    from .contributions import Contributions, ContributionsResult
    from .envelope import Envelope, EnvelopeResult
    from .montecarlo import MonteCarlo, MonteCarloResult
    from .report import Report
    from .sweep import RotateLoad, Sweep, SweepResult, Vary

__version__ = "0.1.0"

#: The studies, imported on first use (they bring SciPy's statistics and pandas).
_STUDIES = {
    "MonteCarlo": "montecarlo",
    "MonteCarloResult": "montecarlo",
    "Envelope": "envelope",
    "EnvelopeResult": "envelope",
    "Sweep": "sweep",
    "SweepResult": "sweep",
    "Vary": "sweep",
    "RotateLoad": "sweep",
    "Contributions": "contributions",
    "ContributionsResult": "contributions",
    "Report": "report",
}


def __getattr__(name: str) -> object:
    if name in _STUDIES:
        import importlib

        return getattr(importlib.import_module(f".{_STUDIES[name]}", __name__), name)
    raise AttributeError(f"module 'jointplay' has no attribute {name!r}")


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
    "OptionError",
    "Report",
    "Result",
    "RotateLoad",
    "SolverError",
    "SolverSettings",
    "Sweep",
    "SweepResult",
    "UnboundedMechanismError",
    "Vary",
    "Workspace",
    "__version__",
    "load",
    "model_from_dict",
    "solve",
    "solve_cases",
]
