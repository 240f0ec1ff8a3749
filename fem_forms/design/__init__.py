"""Design: the rest shape (parameters.py) found by inverse elastostatics (direct.py), the adjoint method
(forward_on_rest.py, adjoint.py, optimizers.py) or the fixed-point baseline; rest-shape files and checks."""
