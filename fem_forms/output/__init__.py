"""Output: results.json (results.py), ParaView fields (fields.py), pictures (pictures.py), probes and sound;
stresses and strains by name (quantities.py: recovered by L2 projection in recovery.py, numpy measures in
measures.py) and support reactions with the equilibrium check (reactions.py)."""
