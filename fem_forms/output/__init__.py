"""Output: results.json (results.py), ParaView fields (fields.py), pictures (pictures.py), probes and sound."""
