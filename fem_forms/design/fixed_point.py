"""The backward-displacement baseline: rest <- target - u(rest)."""
from __future__ import annotations

import time

from dolfinx import fem
from mpi4py import MPI
import numpy as np

from fem_forms.design.forward_on_rest import ForwardOnRest
from fem_forms.design.parameters import InverseResult, target_scene
from fem_forms.meshes import LoadedMesh, load_mesh, mesh_size
from fem_forms.scene import Scene


def solve_fixed_point(scene: Scene, material=None, loaded: LoadedMesh | None = None) -> InverseResult:
    """Backward-displacement iteration: rest <- target - u(rest), i.e. d <- -u(d), until the update
    is below tolerance x mesh size."""
    t0 = time.perf_counter()
    loaded = loaded or load_mesh(target_scene(scene))
    fwd = ForwardOnRest(scene, material, loaded)
    V = fwd.V
    size = mesh_size(loaded.mesh)
    comm = loaded.mesh.comm
    history, ok, msg = [], False, ""
    for k in range(scene.inverse.iterations):
        rep = fwd.solve()
        if not rep.converged:
            msg = f"forward solve failed at iteration {k}: {rep.message}"
            break
        new = -fwd.u.x.array
        change = comm.allreduce(float(np.abs(new - fwd.d.x.array).max()) if new.size else 0.0, op=MPI.MAX)
        fwd.d.x.array[:] = new
        history.append({"iteration": k, "update": change})
        if change <= max(scene.inverse.tolerance, 1e-12) * size:
            ok, msg = True, f"converged: update {change:.3e} m"
            break
        if not np.isfinite(change) or change > 10 * size:
            msg = f"diverged: update {change:.3e} m at iteration {k}"
            break
    else:
        msg = f"no convergence in {scene.inverse.iterations} iterations (last update {history[-1]['update']:.3e} m)"
    v = fem.Function(V, name="rest_minus_target")
    v.x.array[:] = fwd.d.x.array
    res = InverseResult("fixed-point", v, loaded, ok, len(history), msg, history=history,
                        forward_solves=fwd.solves, physics=fwd.physics)
    res.solve_time = time.perf_counter() - t0
    return res

