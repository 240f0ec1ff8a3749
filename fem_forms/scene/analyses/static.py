"""Static analysis: equilibrium under the scene's loads. It owns no section of its own."""
from fem_forms.scene.analyses import Analysis

ANALYSIS = Analysis(
    name="static",
    doc="equilibrium under the loads (load stepping, Newton)",
    runner="fem_forms.analyses.static:run",
    outputs=("results.json", "fields.xdmf", "deformed.png", "newton_history.csv"),
    formulations=("displacement", "mixed"),
)
