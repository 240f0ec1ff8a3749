"""Static analysis: equilibrium under the scene's loads (and, with [thermal], a steady temperature's strain)."""
from fem_forms.scene.analyses import Analysis
from fem_forms.scene.analyses.contact_section import CONTACT
from fem_forms.scene.analyses.fracture_section import FRACTURE
from fem_forms.scene.analyses.thermal_section import THERMAL, check_coupled

ANALYSIS = Analysis(
    name="static",
    doc="equilibrium under the loads (load stepping, Newton)",
    runner="fem_forms.analyses.static:run",
    outputs=("results.json", "fields.xdmf", "deformed.png", "deformed.stl", "newton_history.csv"),
    formulations=("displacement", "mixed"),
    sections=(THERMAL, CONTACT, FRACTURE),   # [thermal]: steady temperature, then its thermal strain; [contact];
                                             # [fracture]: damage, alternate minimization per load step
    check=check_coupled,
)
