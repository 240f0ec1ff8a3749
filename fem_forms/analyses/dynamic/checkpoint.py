"""Checkpoints of a dynamic run and --restart: each rank saves its local arrays (u, v, a, with [thermal] T, and a
plastic solid's history at its quadrature points), and rank 0 the time, step, dt, counters, energies,
probe rows and wall time so far, and the histories of the run's keepers (the impact recorder's contact forces). A restart needs the same number of ranks
(the same partitioning) and continues to the same answer as an uninterrupted run."""
from __future__ import annotations

import json
import os
from pathlib import Path

from mpi4py import MPI
import numpy as np

from fem_forms.analyses.dynamic.energy import Energies
from fem_forms.errors import InputError

def save(folder: Path, result, t: float, step: int, dt: float) -> None:
    """Write the state after an accepted, committed step (each rank its own file, then rank 0 meta)."""
    system = result.system
    comm = system.model.mesh.comm
    if comm.rank == 0:
        folder.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    arrays = {k: f.x.array for k, f in {**system.state.fields, **system.state.history}.items()}
    tmp = folder / f".rank{comm.rank}.npz"
    np.savez(tmp, **arrays)
    os.replace(tmp, folder / f"rank{comm.rank}.npz")
    comm.barrier()
    if comm.rank == 0:
        r = result.report
        meta = {"ranks": comm.size, "time": t, "step": step, "dt": dt,
                "report": {"steps": r.steps, "time_reached": r.time_reached, "dt_min": r.dt_min,
                           "dt_max": r.dt_max, "newton_iterations": r.newton_iterations, "rejected": r.rejected,
                           "refined": r.refined},
                "energies": [[tt, e.row()] for tt, e in result.energy.history],
                "probe_rows": result.probe_rows, "wall_time_s": result.elapsed(),
                "terms": system.model.terms.saved()}
        kept = {f"{i}/{k}": v for i, keeper in enumerate(result.keepers) for k, v in keeper.saved().items()}
        np.savez(folder / ".kept.npz", **kept)              # the keepers' histories (the same on every rank)
        os.replace(folder / ".kept.npz", folder / "kept.npz")
        tmp = folder / ".meta.json"
        tmp.write_text(json.dumps(meta))
        os.replace(tmp, folder / "meta.json")
    comm.barrier()


def load(out: Path, result) -> tuple[float, int, float]:
    """Restore the state saved under out/checkpoint; (time, step, dt) to continue from."""
    system = result.system
    comm = system.model.mesh.comm
    folder = Path(out) / "checkpoint"
    if not (folder / "meta.json").is_file():
        raise InputError(f"--restart {out}: no checkpoint there (checkpoint/meta.json missing)")
    meta = json.loads((folder / "meta.json").read_text())
    if meta["ranks"] != comm.size:
        raise InputError(f"--restart {out}: the checkpoint was written by {meta['ranks']} ranks; "
                         f"run with the same number (this run has {comm.size})")
    data = np.load(folder / f"rank{comm.rank}.npz")
    state = system.state
    fits = all(k in data and data[k].shape == f.x.array.shape for k, f in {**state.fields, **state.history}.items())
    if not comm.allreduce(fits, op=MPI.LAND):
        raise InputError(f"--restart {out}: the checkpoint is of another mesh, discretization or material "
                         "(its fields or plastic history do not match this scene's)")
    state.restore({k: data[k] for k in {**state.fields, **state.history}})
    for name, value in meta["report"].items():
        setattr(result.report, name, value)
    result.energy.history = [(t, Energies(*row)) for t, row in meta["energies"]]
    result.energy.now = result.energy.history[-1][1]
    result.probe_rows = [list(r) for r in meta["probe_rows"]]
    result.wall_before = meta.get("wall_time_s", 0.0)
    system.model.terms.restore(meta.get("terms", []))     # what the terms kept beside the fields (kappa)
    if result.keepers and (folder / "kept.npz").is_file():
        kept = np.load(folder / "kept.npz")
        for i, keeper in enumerate(result.keepers):
            keeper.restore({k.split("/", 1)[1]: kept[k] for k in kept.files if k.startswith(f"{i}/")})
    return meta["time"], meta["step"], meta["dt"]
