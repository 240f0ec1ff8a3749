"""Heat conduction: steady or transient temperature, written for ParaView (temperature.xdmf, with time),
probes.csv (NAME_T columns) and results.json (max_temperature, probes.NAME.temperature)."""
from __future__ import annotations

from pathlib import Path

from dolfinx import io
from mpi4py import MPI

from fem_forms.analyses.thermal.solve import ThermalResult, solve_thermal
from fem_forms.output import fields, results
from fem_forms.scene import Scene

__all__ = ["ThermalResult", "run", "solve_thermal"]


def write_probes_csv(path: Path, names: list, rows: list, comm) -> None:
    """time, NAME_T, ... for every step (rank 0 writes)."""
    if comm.rank == 0:
        lines = [",".join(["time"] + [f"{n}_T" for n in names])]
        lines += [",".join(f"{x:.10g}" for x in row) for row in rows]
        path.write_text("\n".join(lines) + "\n")
    comm.barrier()


def run(scene: Scene, out, echo: bool = False) -> dict:
    """CLI entry: solve, write temperature.xdmf and probes.csv, then results.json last."""
    out = Path(out)
    comm = MPI.COMM_WORLD
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    xdmf, p1 = None, None

    def frame(T, t):
        nonlocal xdmf, p1
        if xdmf is None:
            xdmf = io.XDMFFile(comm, str(out / "temperature.xdmf"), "w")
            xdmf.write_mesh(T.function_space.mesh)
            p1 = fields.p1_interpolant(T, "temperature")
        p1.interpolate(T)
        xdmf.write_function(p1, t)

    try:
        result = solve_thermal(scene, on_frame=frame if scene.output.fields else None)
    finally:
        if xdmf is not None:
            xdmf.close()
    files = {}
    if scene.output.fields:
        files["temperature"] = "temperature.xdmf"
    if scene.output.probes:
        write_probes_csv(out / "probes.csv", list(scene.output.probes), result.probe_rows, comm)
        files["probes"] = "probes.csv"
    summary = result.summary()
    summary["files"] = files
    results.write_json_atomic(out / "results.json", summary, comm)
    if echo and comm.rank == 0:
        kind = f"{summary['steps']} steps to t = {summary['time_reached']:.6g} s" if summary["transient"] else "steady"
        print(f"{scene.title}: {summary['dofs']} dofs, {kind}, max T = {summary['max_temperature']:.6g}, "
              f"{summary['wall_time_s']:.2f} s -> {out}")
        for name, pr in summary["probes"].items():
            print(f"  probe {name} {pr['point']}: T = {pr['temperature']:.6g}")
    return summary
