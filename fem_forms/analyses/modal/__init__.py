"""Modal analysis: vibration modes of a part, K phi = omega^2 M phi (solve.py: at rest or prestressed, supported
or free; band.py: every mode below a frequency, counted by inertia), shared with the sound of an impact; written
as results.json, modes.xdmf, a picture and with [sound] a WAV (outputs.py)."""
from fem_forms.analyses.modal.solve import ModalResult, Operators, assemble_operators, solve_modal
from fem_forms.analyses.modal.outputs import run, write_modal_outputs

__all__ = ["ModalResult", "Operators", "assemble_operators", "run", "solve_modal", "write_modal_outputs"]
