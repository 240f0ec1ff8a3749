"""The bare dolfinx/PETSc side of benchmarks/dynamic_steps.py: the same cantilever march written inline
(the generalized-alpha incremental potential with the consistent mass, or the explicit residual with the
HRZ diagonal), importing nothing from fem_forms; also the problem's numbers that both sides share."""
from __future__ import annotations

import time

SIZES = [(50, 5, 5), (80, 8, 8), (140, 14, 14)]      # P1: 5,508 / 19,683 / 95,175 dofs
WARMUP_CELLS = (4, 1, 1)
SCHEMES = ("newmark", "generalized-alpha", "central-difference")
LU_STEPS = 4                 # the bare variant that factors at every Newton step: fewer steps suffice
STEPS = {"newmark": 8, "generalized-alpha": 8, "central-difference": 100}
LENGTH, WIDTH = 1.0, 0.1
E, NU, RHO = 1.0e8, 0.3, 1000.0
GRAVITY = (0.0, 0.0, -9.81)
DEGREE, QUADRATURE = 1, 2
DT_IMPLICIT, RHO_INF = 1e-3, 0.8
TIP = [LENGTH, 0.5 * WIDTH, 0.5 * WIDTH]

# The implicit bare path's PETSc options, written out literally; the parent checks that ours used these.
BARE_SNES = {"snes_type": "newtonls", "snes_max_it": 50, "snes_rtol": 1e-9, "snes_atol": 0.0,
             "snes_stol": 1e-11, "snes_linesearch_max_it": 40, "snes_linesearch_type": "basic",
             "ksp_type": "gmres", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps",
             "ksp_gmres_restart": 100, "ksp_rtol": 1e-6, "ksp_max_it": 100,
             "snes_lag_preconditioner": 100, "snes_lag_preconditioner_persists": True,
             "snes_lag_jacobian": 100, "snes_lag_jacobian_persists": True}
BARE_LU = {**{k: v for k, v in BARE_SNES.items() if not k.startswith(("ksp_", "snes_lag"))},
           "ksp_type": "preonly"}


def p1_dofs(cells) -> int:
    n, m, k = cells
    return (n + 1) * (m + 1) * (k + 1) * 3


def chung_hulbert(rho_inf: float) -> tuple:
    am = (2 * rho_inf - 1) / (rho_inf + 1)
    af = rho_inf / (rho_inf + 1)
    return am, af, 0.25 * (1 - am + af) ** 2, 0.5 - am + af


def params(scheme: str) -> tuple:
    return chung_hulbert(RHO_INF) if scheme == "generalized-alpha" else (0.0, 0.0, 0.25, 0.5)


def now():
    """(wall, CPU) seconds: under load from other jobs wall times of ms-long steps jump by scheduler time
    slices (measured: the same 1 ms energy update took 1.2 or 9.4 ms), CPU times far less."""
    import numpy as np
    return np.array([time.perf_counter(), time.process_time()])


def split(pair, key: str) -> dict:
    """{key: wall, key_cpu: CPU} from a (wall, CPU) pair."""
    return {key: float(pair[0]), key + "_cpu": float(pair[1])}


def lu_count() -> tuple[int, float]:
    from petsc4py import PETSc
    info = PETSc.Log.Event("MatLUFactorNum").getPerfInfo()
    return int(info["count"]), float(info["time"])


def bare_run(cells, scheme: str, dt: float, steps: int, lu_every_newton: bool = False) -> dict:
    """The same march with plain dolfinx 0.5.2 and petsc4py calls."""
    import numpy as np
    import ufl
    from dolfinx import fem, mesh as dmesh
    from dolfinx.fem import petsc as fpetsc
    from mpi4py import MPI
    from petsc4py import PETSc

    lu0 = lu_count()
    t0 = now()
    comm = MPI.COMM_WORLD
    msh = dmesh.create_box(comm, [np.zeros(3), np.array([LENGTH, WIDTH, WIDTH])], list(cells),
                           cell_type=dmesh.CellType.tetrahedron)
    V = fem.VectorFunctionSpace(msh, ("Lagrange", DEGREE))
    u, u0, v0, a0 = (fem.Function(V) for _ in range(4))
    clamped = dmesh.locate_entities_boundary(msh, 2, lambda x: np.isclose(x[0], 0.0))
    fixed = fem.locate_dofs_topological(V, 2, clamped)
    bcs = [fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), fixed, V)]
    c = lambda x: fem.Constant(msh, PETSc.ScalarType(x))       # noqa: E731
    rho, g = c(RHO), c(GRAVITY)
    mu, lmbda = c(E / (2 * (1 + NU))), c(E * NU / ((1 + NU) * (1 - 2 * NU)))
    dx = ufl.Measure("dx", domain=msh, metadata={"quadrature_degree": QUADRATURE})
    test = ufl.TestFunction(V)

    def potential(w):
        F = ufl.Identity(3) + ufl.grad(w)
        J = ufl.det(F)
        psi = 0.5 * mu * (ufl.tr(F.T * F) - 3) - mu * ufl.ln(J) + 0.5 * lmbda * ufl.ln(J) ** 2
        return psi * dx - rho * ufl.dot(g, w) * dx

    n = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
    b0 = fpetsc.assemble_vector(fem.form(ufl.derivative(potential(u), u, test)))   # at rest: a0 = -M^-1 R
    b0.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    b0.scale(-1.0)
    fpetsc.set_bc(b0, bcs, scale=0.0)
    bare = dict(u=u, u0=u0, v0=v0, a0=a0, bcs=bcs, potential=potential, rho=rho, dx=dx, n=n, b0=b0, dt=dt,
                steps=steps, scheme=scheme)
    if scheme == "central-difference":
        t_setup, stamps, newton, krylov = _march_explicit(bare)
    else:
        t_setup, stamps, newton, krylov = _march_implicit(bare, BARE_LU if lu_every_newton else BARE_SNES)
    d = np.diff(np.array([t_setup] + stamps), axis=0)
    lu = lu_count()
    vals = u.x.array.reshape(-1, 3)
    return {"dofs": V.dofmap.index_map.size_global * V.dofmap.index_map_bs, **split(t_setup - t0, "setup"),
            **split(stamps[-1] - t0, "total"), "steps": steps, **split(d[0], "first"),
            **split(np.median(d[1:], axis=0), "later"),
            "newton": newton, "krylov": krylov, "lu": lu[0] - lu0[0], "lu_time": lu[1] - lu0[1], "dt": dt,
            "max_u": comm.allreduce(float(np.linalg.norm(vals, axis=1).max()), op=MPI.MAX),
            "options": (BARE_LU if lu_every_newton else BARE_SNES) if scheme != "central-difference" else None}


def _march_explicit(bare: dict) -> tuple:
    """Central differences with the HRZ-lumped mass: (setup stamp, step stamps, 0, 0)."""
    import ufl
    from dolfinx import fem
    from dolfinx.fem import petsc as fpetsc
    from mpi4py import MPI
    from petsc4py import PETSc

    u, v0, a0, bcs, n, dt = bare["u"], bare["v0"], bare["a0"], bare["bcs"], bare["n"], bare["dt"]
    V = u.function_space
    test, trial = ufl.TestFunction(V), ufl.TrialFunction(V)
    M = fpetsc.assemble_matrix(fem.form(bare["rho"] * ufl.inner(trial, test) * bare["dx"]))
    M.assemble()
    inv = M.getDiagonal()
    total = V.mesh.comm.allreduce(fem.assemble_scalar(fem.form(bare["rho"] * bare["dx"])), op=MPI.SUM)
    inv.scale(3.0 * total / inv.sum())                       # HRZ
    inv.reciprocal()
    owned = bcs[0].dof_indices()[0][: bcs[0].dof_indices()[1]]
    inv.array[owned[owned < n]] = 0.0
    a0.x.array[:n] = bare["b0"].array * inv.array
    a0.x.scatter_forward()
    L = fem.form(ufl.derivative(bare["potential"](u), u, test))
    b = fpetsc.create_vector(L)
    t_setup = now()
    stamps = []
    for _ in range(bare["steps"]):
        vh = v0.x.array + 0.5 * dt * a0.x.array
        u.x.array[:] += dt * vh
        with b.localForm() as bl:
            bl.set(0.0)
        fpetsc.assemble_vector(b, L)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        a0.x.array[:n] = -b.array * inv.array
        a0.x.scatter_forward()
        v0.x.array[:] = vh + 0.5 * dt * a0.x.array
        stamps.append(now())
    return t_setup, stamps, 0, 0


def _march_implicit(bare: dict, options: dict) -> tuple:
    """Generalized-alpha (or Newmark) steps, each solved by BareSNES with `options`: (setup stamp, step stamps,
    Newton iterations, Krylov iterations)."""
    import ufl
    from dolfinx import fem
    from dolfinx.fem import petsc as fpetsc
    from petsc4py import PETSc

    from bare_snes import BareSNES

    u, u0, v0, a0, bcs, dt = bare["u"], bare["u0"], bare["v0"], bare["a0"], bare["bcs"], bare["dt"]
    V, rho, dx = u.function_space, bare["rho"], bare["dx"]
    msh = V.mesh
    test, trial = ufl.TestFunction(V), ufl.TrialFunction(V)
    M = fpetsc.assemble_matrix(fem.form(rho * ufl.inner(trial, test) * dx), bcs=bcs)
    M.assemble()
    ksp = PETSc.KSP().create(msh.comm)
    ksp.setOperators(M)
    ksp.setType("cg")
    ksp.getPC().setType("jacobi")
    ksp.setTolerances(rtol=1e-12, atol=1e-300, max_it=2000)
    ksp.solve(bare["b0"], a0.vector)
    a0.x.scatter_forward()
    p_am, p_af, p_beta, p_gamma = params(bare["scheme"])
    am, af, beta = (fem.Constant(msh, PETSc.ScalarType(p)) for p in (p_am, p_af, p_beta))
    k_dt = fem.Constant(msh, PETSc.ScalarType(dt))
    # the generalized-alpha incremental potential in u = u_{n+1}: (1 - alpha_m) M a(u) + alpha_m M a_n
    # + f_int(u_f) - f_ext is its gradient (Newmark average acceleration: alpha_m = alpha_f = 0)
    pred = u0 + k_dt * v0 + k_dt * k_dt * (0.5 - beta) * a0
    inertia = rho * ((1 - am) / (2 * beta * k_dt * k_dt) * ufl.inner(u - pred, u - pred)
                     + am * ufl.inner(a0, u)) * dx
    Pi = (1 / (1 - af)) * bare["potential"]((1 - af) * u + af * u0) + inertia
    R = ufl.derivative(Pi, u, test)
    L, a, energy = fem.form(R), fem.form(ufl.derivative(R, u, trial)), fem.form(Pi)
    solver = BareSNES(u, L, a, energy, bcs, options)
    snes = solver.snes
    t_setup = now()
    stamps, newton, krylov = [], 0, 0
    for _ in range(bare["steps"]):
        uo, vo, ao = u0.x.array, v0.x.array, a0.x.array
        u.x.array[:] = uo + dt * vo            # the same (constant-velocity) predictor as ours
        reason = solver.solve()
        assert reason > 0, reason
        newton += snes.getIterationNumber()
        krylov += snes.getLinearSolveIterations()
        anew = (u.x.array - uo - dt * vo - dt * dt * (0.5 - p_beta) * ao) / (p_beta * dt * dt)
        v0.x.array[:] = vo + dt * ((1 - p_gamma) * ao + p_gamma * anew)
        a0.x.array[:] = anew
        u0.x.array[:] = u.x.array
        stamps.append(now())
    solver.destroy()
    return t_setup, stamps, newton, krylov
