"""Numerical studies of the twin (``twin study ...``): accuracy versus run time, stability."""
