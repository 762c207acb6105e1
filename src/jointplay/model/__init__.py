"""The model layer: a mechanism as validated, immutable data (units, fields,
tolerances and fits, joint types, bodies, loads and requirements)."""
