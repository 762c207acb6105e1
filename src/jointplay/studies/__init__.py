"""Studies over one mechanism: Monte Carlo, sweeps, worst-case envelopes and
contributions, each a settings object with a ``run``."""
