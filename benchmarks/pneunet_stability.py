"""Is each accepted state of the PneuNet demo's volume-controlled path stable? Under one volume constraint an
equilibrium is stable when the pressure-control tangent K (the driver's, follower pressure included) is positive
definite, or has exactly one negative eigenvalue and q = c_u.K^-1 c_u < 0 (the constraint holds that mode: what
volume control is for); with two negative eigenvalues, or one and q > 0, it is a saddle a real actuator snaps
away from. The inertia comes from MUMPS's LDL^T (INFOG(12): negative pivots), the sign of q from the bordered
solve's Schur complement S = q / s (s > 0, physics/cavities.py). Serial.

    .venv/bin/python benchmarks/pneunet_stability.py [H] [VOLUME_ML]     # default: the demo's 6 mm mesh, 22 ml
"""
import sys
import tempfile
from pathlib import Path

from mpi4py import MPI
from petsc4py import PETSc

import fem_forms as ff
from fem_forms.analyses.static.solve import load_path
from fem_forms.model import build_model
from fem_forms.physics.cavities import cavity_report
from fem_forms.solvers import continuation
from fem_forms.solvers.snes import SNESDriver

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "demos" / "geometry"))
import pneunet  # noqa: E402


def negative_pivots(A: PETSc.Mat) -> int:
    """Negative eigenvalues of the symmetric matrix A (Sylvester: negative pivots of MUMPS's LDL^T)."""
    M = A.copy()
    M.convert("aij")
    M.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    ksp = PETSc.KSP().create(A.comm)
    ksp.setOperators(M)
    ksp.setType("preonly")
    pc = ksp.getPC()
    pc.setType("cholesky")
    pc.setFactorSolverType("mumps")
    ksp.setUp()
    n = pc.getFactorMatrix().getMumpsInfog(12)
    ksp.destroy()
    M.destroy()
    return n


def main() -> None:
    h = float(sys.argv[1]) if len(sys.argv) > 1 else 0.006
    volume = float(sys.argv[2]) * 1e-6 if len(sys.argv) > 2 else None
    ff.quiet_jit()
    with tempfile.TemporaryDirectory() as tmp:
        msh = pneunet.build(Path(tmp) / "pneunet.msh", h, layer=pneunet.LAYER)
        overrides = {"mesh.file": str(msh)} | ({"load.0.volume": volume} if volume else {})
        scene = ff.Scene.from_file(ROOT / "demos" / "scenes" / "pneunet.toml", overrides=overrides)
        model = build_model(scene)
        set_load, _ = load_path(model)
        problem = model.problem(set_load)
        drv = SNESDriver(problem, {}, "direct", "stability_", None, False)
        print(f"h = {h * 1e3:g} mm, {drv.dofs} dofs")
        print("| load factor | volume [ml] | pressure [kPa] | negative pivots of K | sign of q | stable |")
        print("|---:|---:|---:|---:|---:|---|")

        def check(lam: float) -> None:
            b = drv.bordered
            X = b.pack(problem.u.vector).copy()
            b.jacobian(None, X, b.J, b.J)         # K at the accepted state, and the Schur complement S = q / s
            neg, q = negative_pivots(drv.A), b.S[0, 0]
            cav = cavity_report(model.terms)["chambers"]
            stable = neg == 0 or (neg == 1 and q < 0)
            print(f"| {lam:.5f} | {cav['volume_change'] * 1e6:.3f} | {cav['pressure'] / 1e3:.3f} | {neg} | "
                  f"{'-' if q < 0 else '+'} | {'yes' if stable else 'no'} |", flush=True)
            X.destroy()

        report = continuation.solve(problem, {}, steps=scene.solver.steps, driver=drv, on_step=check)
        print(f"converged {report.converged}: {report.message}")


if __name__ == "__main__":
    if MPI.COMM_WORLD.size > 1:
        if MPI.COMM_WORLD.rank == 0:
            print("pneunet_stability.py: runs serially (it reads one MUMPS factor's inertia); run it without mpirun",
                  file=sys.stderr)
        sys.exit(2)
    main()
