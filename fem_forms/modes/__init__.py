"""Vibration modes of a part, K phi = omega^2 M phi (solve.py: at rest or prestressed, supported or free; band.py:
every mode below a frequency, counted by inertia): shared by the modal analysis and the sound of an impact."""
from fem_forms.modes.solve import ModalResult, Operators, assemble_operators, solve_modal

__all__ = ["ModalResult", "Operators", "assemble_operators", "solve_modal"]
