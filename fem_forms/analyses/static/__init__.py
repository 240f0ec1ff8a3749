"""Static analysis: equilibrium under the scene's loads (solve.py, the one static solve the modal prestress, the
inverse design's forward check and the balance sag share; heat.py, a coupled steady temperature solved first),
then fields, pictures and results.json (outputs.py)."""
from fem_forms.analyses.static.solve import StaticResult, solve_static
from fem_forms.analyses.static.outputs import run, solve_and_write, write_static_outputs

__all__ = ["StaticResult", "run", "solve_and_write", "solve_static", "write_static_outputs"]
