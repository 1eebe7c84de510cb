"""Network building blocks shared by policies and predictors, in plain torch and numba (no training dependency)."""
