"""Model files in and out: reading YAML/JSON into a validated model, and the
generated test mechanisms."""
