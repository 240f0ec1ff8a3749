"""The library of named materials makers buy (library.toml: casting silicones as published fits, printing
filaments as datasheet constants), each with its source; `library = "name"` in a [[material]] table."""
from __future__ import annotations

from pathlib import Path
import tomllib

LIBRARY_FILE = Path(__file__).with_name("library.toml")
# the keys of an entry that are model parameters (scene keys), beside model, rho, yield and the record
PARAMETERS = ("E", "nu", "mu", "lambda", "C10", "C01", "C20", "C30", "alpha", "Jm", "lambda_m", "bulk")
RECORD = ("title", "kind", "shore", "source", "year", "note")


def _load() -> dict:
    with open(LIBRARY_FILE, "rb") as f:
        return tomllib.load(f)


LIBRARY: dict = _load()


def parameters(name: str) -> dict:
    """The model parameters of a library entry (scene key -> value)."""
    return {k: v for k, v in LIBRARY[name].items() if k in PARAMETERS}


def record(name: str) -> dict:
    """What results.json says about where a library material comes from."""
    e = LIBRARY[name]
    return {"name": name, **{k: e[k] for k in RECORD if k in e}}
