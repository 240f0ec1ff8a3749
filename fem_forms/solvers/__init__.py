"""Solvers: the SNES driver (snes.py), load continuation (continuation.py), linear solver choices
(linear.py, preconditioner_reuse.py) and the SLEPc eigensolver (eigen.py)."""
