"""results.json (written last and atomically) and the Newton history CSV."""
from __future__ import annotations

import json
import math
import os
from pathlib import Path
import tempfile

from mpi4py import MPI
import numpy as np


def _clean(obj):
    """JSON-safe copy: NaN/Inf become null, numpy scalars become Python numbers."""
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


def write_json_atomic(path: Path, data: dict, comm: MPI.Comm = MPI.COMM_WORLD) -> None:
    """Rank 0 writes to a temporary file beside `path` and renames it: complete or absent. Any exception
    during the write, KeyboardInterrupt included, removes the temporary file and leaves `path` as it was."""
    if comm.rank == 0:
        path.parent.mkdir(parents=True, exist_ok=True)
        text = json.dumps(_clean(data), indent=2)           # serialise before any file exists
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".results-", suffix=".json")
        try:
            with os.fdopen(fd, "w") as f:
                f.write(text)
            os.chmod(tmp, 0o644)
            os.replace(tmp, path)
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise
    comm.barrier()


def forget_results(path: Path, comm: MPI.Comm = MPI.COMM_WORLD) -> None:
    """Remove an earlier run's results.json before solving again: if this run is interrupted or fails
    before it writes its own, no old answer is left that looks like the new one."""
    if comm.rank == 0:
        path.unlink(missing_ok=True)
    comm.barrier()


def write_newton_history(path: Path, steps: list, comm: MPI.Comm = MPI.COMM_WORLD) -> None:
    """CSV: step, load factor, accepted, SNES reason, Newton iteration, residual norm."""
    if comm.rank == 0:
        lines = ["step,load,accepted,reason,iteration,residual"]
        for k, s in enumerate(steps):
            for i, r in enumerate(s.residuals):
                lines.append(f"{k},{s.load:.6g},{int(s.accepted)},{s.reason},{i},{r:.6e}")
        path.write_text("\n".join(lines) + "\n")
    comm.barrier()

