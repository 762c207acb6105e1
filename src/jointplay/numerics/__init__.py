"""Linear algebra the solver needs: sparse-or-dense helpers, KKT solves and
the free motions of a mechanism, found body by body."""
